// SPDX-License-Identifier: Apache-2.0
/// @file FrameSequence.h
/// @brief Frame sequences for `nonbloppy mesh`: file-name patterns with a frame placeholder,
///        `--frames` lists, and the plan of which frames a run reads and writes.
///
/// Placeholders (one per name):
/// - `{}`      any number of digits, any zero padding (as splashsurf). An output `{}` gets
///             the digits exactly as the input's file name spells them.
/// - `####`    exactly as many digits as `#` (zero-padded; more digits only for larger numbers),
///             as Houdini's `$F4`.
/// - `%04d`    printf style, as Nuke: `%0Nd` zero-pads to N digits, `%d` does not pad.
///
/// @code
/// FramePattern in = parseFramePattern("sim/fluid_{}.vtk", "IN");
/// FramePattern out = parseFramePattern("mesh/fluid_####.obj", "--output");
/// FramePlan plan = planFrames(in, parseFrameList("1-240:2", "--frames"));
/// for (const Frame& f : plan.frames) mesh(f.input, out.path(f));
/// @endcode
/// Errors are nonbloppy::ParameterError / FileError with one line naming the option or file.

#ifndef NONBLOPPY_TOOL_FRAME_SEQUENCE_H
#define NONBLOPPY_TOOL_FRAME_SEQUENCE_H

#include <optional>
#include <string>
#include <vector>

namespace nonbloppy_tool {

/// One frame of a sequence found on disk.
struct Frame
{
    int number = 0;
    std::string digits;   ///< the number as the input file name spells it ("0012")
    std::string input;    ///< the input file's path
    /// Another file that names the same frame ("fluid_01.vtk" beside "fluid_1.vtk"), or empty;
    /// planFrames() refuses such a frame only when the run asks for it.
    std::string otherInput;
};

/// A file name with at most one frame-number placeholder.
class FramePattern
{
public:
    enum class Kind { None, Braces, Hashes, Printf };

    Kind kind() const { return mKind; }
    bool hasPlaceholder() const { return mKind != Kind::None; }
    /// The pattern as given.
    const std::string& text() const { return mText; }
    /// Minimum number of digits (0 for `{}` and `%d`).
    int width() const { return mWidth; }

    /// The name of frame @a number; `{}` writes the number without padding.
    std::string path(int number) const;
    /// The name for @a frame; `{}` writes frame.digits (the input's spelling).
    std::string path(const Frame& frame) const;

    /// If the last path component @a fileName fits the pattern's file name, the frame's digits.
    /// `####` and `%04d` accept exactly the digits path() would write for the number.
    std::optional<std::string> matchFileName(const std::string& fileName) const;
    /// The digits where the placeholder stands in @a fileName, whatever number they spell
    /// (matchFileName() also wants a number that fits an int, spelled the pattern's way).
    std::optional<std::string> matchDigits(const std::string& fileName) const;

    /// The directory part of the pattern ("" for the current directory).
    std::string directory() const;
    /// The pattern's text before the file name, as typed ("sim//", "" for the current
    /// directory): the frames' paths start with it, so that a frame is named alike in a
    /// sequence and alone ("sim//f_{}.vtk" gave "sim/f_1.vtk", recorded in its .vdb).
    std::string directoryPrefix() const;

private:
    friend FramePattern parseFramePattern(const std::string& text, const std::string& what);
    std::string mText, mPrefix, mSuffix;
    Kind mKind = Kind::None;
    int mWidth = 0;
};

/// Find the placeholder in the file name of @a text; placeholders in its directories are
/// part of their names ("shot#2/fluid_{}.vtk" is a sequence in the directory "shot#2").
/// @a what names the option in errors ("IN", "--output"): "--output: more than one frame placeholder in 'a_{}_{}.obj'".
/// @throw nonbloppy::ParameterError
FramePattern parseFramePattern(const std::string& text, const std::string& what);

/// Whether a directory of @a path spells a placeholder ("take_{}/fluid.vtk"): a sequence
/// whose frames are directories, which nonbloppy does not take, when no such file exists.
bool placeholderInDirectory(const std::string& path);

/// Parse a frame list: "1-240", "1-240:2" (every second frame), "12,15,90-99", "7".
/// Returns the frames in increasing order, without duplicates. Spaces around items are
/// allowed; negative numbers are not. Errors name @a what, e.g. "--frames: bad range '12-3'".
/// @throw nonbloppy::ParameterError
std::vector<int> parseFrameList(const std::string& text, const std::string& what = "--frames");

/// "1-3, 5, 7-9, 20-2000:10": increasing @a frames with runs of one step folded, as
/// parseFrameList() reads them (consecutive frames from two, stepped ones from three).
std::string formatFrameList(std::vector<int> frames);

/// Every frame of @a input on disk, in increasing order.
/// Two files that give the same number are both kept (Frame::otherInput).
/// @throw nonbloppy::FileError if the directory cannot be read.
std::vector<Frame> findFrames(const FramePattern& input);
/// findFrames(), and in @a pastLargest the first name (sorted) of a file that fits the
/// pattern but whose number is past INT_MAX ("" if none).
std::vector<Frame> findFrames(const FramePattern& input, std::string& pastLargest);

/// The frames a run works on.
struct FramePlan
{
    std::vector<Frame> frames;   ///< found and requested, in increasing order
    std::vector<int> missing;    ///< requested but not on disk
    std::vector<Frame> onDisk;   ///< every frame found, requested or not (no output may name one)
};

/// Every frame found when @a requested is empty, else the requested ones that exist
/// (the rest in missing).
/// @throw nonbloppy::FileError naming a file that fits the pattern but whose frame number
///        is past INT_MAX, when @a requested is empty (it would be left out unsaid).
/// @throw nonbloppy::FileError if two files give the number of a planned frame
///        ("fluid_01.vtk and fluid_1.vtk are both frame 1"): a leftover file of frame 1
///        does not stop a run of --frames 2.
FramePlan planFrames(const FramePattern& input, const std::optional<std::vector<int>>& requested);

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_FRAME_SEQUENCE_H
