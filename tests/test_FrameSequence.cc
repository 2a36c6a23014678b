// SPDX-License-Identifier: Apache-2.0
/// @file test_FrameSequence.cc
/// @brief The tool's frame-sequence parsing, in-process: placeholders, names of frames,
///        --frames lists and their errors, frames found on disk.

#include "Commands.h"
#include "FrameSequence.h"

#include <nonbloppy/Error.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using nonbloppy_tool::Frame;
using nonbloppy_tool::FramePattern;
using nonbloppy_tool::formatFrameList;
using nonbloppy_tool::parseFrameList;
using nonbloppy_tool::parseFramePattern;

/// The message of the ParameterError @a f throws ("" if it throws none).
template<typename F>
std::string errorOf(F&& f)
{
    try {
        f();
    } catch (const nonbloppy::Error& e) {
        return e.what();
    }
    return "";
}

TEST(FramePatternTest, RecognisesEachPlaceholder)
{
    EXPECT_EQ(parseFramePattern("sim/fluid_{}.vtk", "IN").kind(), FramePattern::Kind::Braces);
    const FramePattern hashes = parseFramePattern("sim/fluid_####.vtk", "IN");
    EXPECT_EQ(hashes.kind(), FramePattern::Kind::Hashes);
    EXPECT_EQ(hashes.width(), 4);
    const FramePattern printf4 = parseFramePattern("sim/fluid_%04d.vtk", "IN");
    EXPECT_EQ(printf4.kind(), FramePattern::Kind::Printf);
    EXPECT_EQ(printf4.width(), 4);
    EXPECT_EQ(parseFramePattern("fluid_%d.vtk", "IN").width(), 0);
    EXPECT_FALSE(parseFramePattern("sim/fluid_0001.vtk", "IN").hasPlaceholder());
    // '%' not followed by [0N]d is part of the name.
    EXPECT_FALSE(parseFramePattern("100%.vtk", "IN").hasPlaceholder());
    EXPECT_FALSE(parseFramePattern("a%4d.vtk", "IN").hasPlaceholder());
}

TEST(FramePatternTest, MoreThanOnePlaceholderIsAnError)
{
    EXPECT_EQ(errorOf([] { parseFramePattern("a_{}_{}.obj", "--output"); }),
              "--output: more than one frame placeholder in 'a_{}_{}.obj'");
    EXPECT_EQ(errorOf([] { parseFramePattern("a_##_%04d.vtk", "IN"); }),
              "IN: more than one frame placeholder in 'a_##_%04d.vtk'");
}

TEST(FramePatternTest, NamesOfFrames)
{
    EXPECT_EQ(parseFramePattern("out/m_####.obj", "-o").path(12), "out/m_0012.obj");
    EXPECT_EQ(parseFramePattern("out/m_####.obj", "-o").path(123456), "out/m_123456.obj");
    EXPECT_EQ(parseFramePattern("out/m_%05d.obj", "-o").path(7), "out/m_00007.obj");
    EXPECT_EQ(parseFramePattern("out/m_%d.obj", "-o").path(7), "out/m_7.obj");
    EXPECT_EQ(parseFramePattern("out/m_{}.obj", "-o").path(7), "out/m_7.obj");
    // {} in an output copies the input's spelling of the number.
    Frame frame;
    frame.number = 7;
    frame.digits = "007";
    EXPECT_EQ(parseFramePattern("out/m_{}.obj", "-o").path(frame), "out/m_007.obj");
    EXPECT_EQ(parseFramePattern("out/m_##.obj", "-o").path(frame), "out/m_07.obj");
}

TEST(FramePatternTest, MatchesFileNames)
{
    const FramePattern braces = parseFramePattern("sim/fluid_{}.vtk", "IN");
    EXPECT_EQ(braces.matchFileName("fluid_1.vtk").value_or("-"), "1");
    EXPECT_EQ(braces.matchFileName("fluid_0001.vtk").value_or("-"), "0001");
    EXPECT_FALSE(braces.matchFileName("fluid_.vtk"));
    EXPECT_FALSE(braces.matchFileName("fluid_1a.vtk"));
    EXPECT_FALSE(braces.matchFileName("fluid_1.vtk.bak"));
    EXPECT_FALSE(braces.matchFileName("gas_1.vtk"));
    EXPECT_FALSE(braces.matchFileName("fluid_-1.vtk"));

    const FramePattern hashes = parseFramePattern("sim/fluid_####.vtk", "IN");
    EXPECT_EQ(hashes.matchFileName("fluid_0012.vtk").value_or("-"), "0012");
    EXPECT_EQ(hashes.matchFileName("fluid_12345.vtk").value_or("-"), "12345");
    EXPECT_FALSE(hashes.matchFileName("fluid_12.vtk"));
    EXPECT_FALSE(hashes.matchFileName("fluid_00012.vtk"));
    EXPECT_EQ(hashes.directory(), "sim");

    const FramePattern plain = parseFramePattern("fluid_%d.vtk", "IN");
    EXPECT_EQ(plain.matchFileName("fluid_12.vtk").value_or("-"), "12");
    EXPECT_FALSE(plain.matchFileName("fluid_012.vtk"));
    EXPECT_EQ(plain.directory(), "");
}

TEST(FrameListTest, RangesStepsAndLists)
{
    EXPECT_EQ(parseFrameList("1-5"), (std::vector<int>{1, 2, 3, 4, 5}));
    EXPECT_EQ(parseFrameList("1-10:3"), (std::vector<int>{1, 4, 7, 10}));
    EXPECT_EQ(parseFrameList("1-240:2").size(), 120u);
    EXPECT_EQ(parseFrameList("12,15,90-92"), (std::vector<int>{12, 15, 90, 91, 92}));
    EXPECT_EQ(parseFrameList("7"), (std::vector<int>{7}));
    EXPECT_EQ(parseFrameList("0"), (std::vector<int>{0}));
    // Sorted, duplicates dropped, spaces allowed.
    EXPECT_EQ(parseFrameList(" 5 , 1-3, 2 "), (std::vector<int>{1, 2, 3, 5}));
    EXPECT_EQ(parseFrameList("3-3"), (std::vector<int>{3}));
}

TEST(FrameListTest, Errors)
{
    EXPECT_EQ(errorOf([] { parseFrameList("12-3"); }), "--frames: bad range '12-3' (end before start)");
    EXPECT_EQ(errorOf([] { parseFrameList("1-10:0"); }),
              "--frames: bad step in '1-10:0' (must be an integer >= 1)");
    EXPECT_EQ(errorOf([] { parseFrameList("1-10:x"); }),
              "--frames: bad step in '1-10:x' (must be an integer >= 1)");
    EXPECT_EQ(errorOf([] { parseFrameList("5:2"); }),
              "--frames: a step needs a range, as in 1-10:2, got '5:2'");
    EXPECT_EQ(errorOf([] { parseFrameList("1,,3"); }), "--frames: empty item in '1,,3'");
    EXPECT_EQ(errorOf([] { parseFrameList("1,"); }), "--frames: empty item in '1,'");
    EXPECT_EQ(errorOf([] { parseFrameList(""); }), "--frames: empty frame list");
    EXPECT_EQ(errorOf([] { parseFrameList("abc"); }),
              "--frames: bad frame number 'abc' (expected N, A-B or A-B:STEP with A, B >= 0)");
    EXPECT_EQ(errorOf([] { parseFrameList("-5"); }),
              "--frames: bad range '-5' (expected N, A-B or A-B:STEP with A, B >= 0)");
    EXPECT_EQ(errorOf([] { parseFrameList("1-x"); }),
              "--frames: bad range '1-x' (expected N, A-B or A-B:STEP with A, B >= 0)");
    EXPECT_EQ(errorOf([] { parseFrameList("0-2000000000"); }),
              "--frames: more than 10000000 frames in '0-2000000000'");
}

TEST(FrameListTest, NumbersPastAnIntAreSaidToBe)
{
    EXPECT_EQ(errorOf([] { parseFrameList("2147483648"); }),
              "--frames: frame number 2147483648 is past 2147483647, the largest nonbloppy takes");
    EXPECT_EQ(errorOf([] { parseFrameList("1-12345678901"); }),
              "--frames: frame number 12345678901 is past 2147483647, the largest nonbloppy takes");
    EXPECT_EQ(parseFrameList("2147483647"), std::vector<int>{2147483647});
    EXPECT_EQ(parseFrameList("00000000001"), std::vector<int>{1});  // padding, not a large number
    EXPECT_EQ(errorOf([] { parseFrameList("1-2:2147483648"); }),
              "--frames: step 2147483648 is past 2147483647, the largest nonbloppy takes");
}

TEST(FrameListTest, FormatFoldsRuns)
{
    EXPECT_EQ(formatFrameList({1, 2, 3, 5, 7, 8, 9}), "1-3, 5, 7-9");
    EXPECT_EQ(formatFrameList({4}), "4");
    EXPECT_EQ(formatFrameList({}), "");
    EXPECT_EQ(formatFrameList({9, 8, 8}), "8-9");
    // Stepped runs fold too: '--frames 1-2000:2' with three files on disk listed its 997
    // missing frames one by one (at '1-2000000000:1000', a 22 MB line).
    EXPECT_EQ(formatFrameList({7, 9, 11, 13, 20, 21, 30, 32}), "7-13:2, 20-21, 30, 32");
    EXPECT_EQ(formatFrameList({5, 7}), "5, 7");
    std::vector<int> stepped;
    for (int f = 1007; f <= 1999001007; f += 1000) stepped.push_back(f);
    EXPECT_EQ(formatFrameList(stepped), "1007-1999001007:1000");
    EXPECT_EQ(parseFrameList(formatFrameList(stepped)), stepped);
}

class FindFramesTest : public ::testing::Test
{
protected:
    void SetUp() override
    {
        mDir = (fs::path(::testing::TempDir()) / ("nonbloppy_frames_" + std::to_string(::getpid())))
                   .string();
        fs::remove_all(mDir);
        fs::create_directories(mDir);
    }
    void TearDown() override
    {
        std::error_code ec;
        fs::remove_all(mDir, ec);
    }
    void touch(const std::string& name) const { std::ofstream(mDir + "/" + name) << "x"; }
    std::string mDir;
};

TEST_F(FindFramesTest, FindsFramesInOrderAndPlansMissingOnes)
{
    for (const char* name : {"f_0010.vtk", "f_0002.vtk", "f_0003.vtk", "f_0003.obj", "g_0004.vtk",
                             "f_12.vtk", "notes.txt"}) {
        touch(name);
    }
    fs::create_directories(mDir + "/f_0005.vtk"); // a directory is not a frame

    const FramePattern hashes = parseFramePattern(mDir + "/f_####.vtk", "IN");
    const std::vector<Frame> frames = nonbloppy_tool::findFrames(hashes);
    ASSERT_EQ(frames.size(), 3u);
    EXPECT_EQ(frames[0].number, 2);
    EXPECT_EQ(frames[0].digits, "0002");
    EXPECT_EQ(frames[0].input, mDir + "/f_0002.vtk");
    EXPECT_EQ(frames[2].number, 10);

    // {} takes any padding, so f_12.vtk is frame 12 as well.
    const FramePattern braces = parseFramePattern(mDir + "/f_{}.vtk", "IN");
    const nonbloppy_tool::FramePlan all = nonbloppy_tool::planFrames(braces, std::nullopt);
    ASSERT_EQ(all.frames.size(), 4u);
    EXPECT_EQ(all.frames.back().number, 12);
    EXPECT_EQ(all.frames.back().digits, "12");
    EXPECT_TRUE(all.missing.empty());

    const nonbloppy_tool::FramePlan some =
        nonbloppy_tool::planFrames(hashes, parseFrameList("1-4,10"));
    ASSERT_EQ(some.frames.size(), 3u);
    EXPECT_EQ(some.frames[1].number, 3);
    EXPECT_EQ(some.missing, (std::vector<int>{1, 4}));
}

TEST_F(FindFramesTest, AFileWhoseNumberIsPastAnIntIsNamedNotLeftOut)
{
    // f_2147483648.vtk fit the pattern but no int: it was left out of the run unsaid, and
    // alone it gave "no file matches".
    touch("f_1.vtk");
    touch("f_2147483648.vtk");
    touch("f_12345678901.vtk");
    const FramePattern braces = parseFramePattern(mDir + "/f_{}.vtk", "IN");
    EXPECT_EQ(errorOf([&] { nonbloppy_tool::planFrames(braces, std::nullopt); }),
              mDir + "/f_12345678901.vtk: its frame number is past 2147483647, the largest nonbloppy takes; give "
                     "--frames to leave it out");
    const nonbloppy_tool::FramePlan one = nonbloppy_tool::planFrames(braces, parseFrameList("1"));
    ASSERT_EQ(one.frames.size(), 1u);
    EXPECT_EQ(one.frames[0].input, mDir + "/f_1.vtk");
    // A number padded otherwise than #### or %05d asks is another name, not a number past
    // an int (the first version of this check said so of f_07.vtk and stopped the run).
    touch("g_0001.vtk");
    touch("g_07.vtk");
    touch("g_00002.vtk");
    for (const char* pattern : {"/g_####.vtk", "/g_%04d.vtk"}) {
        const nonbloppy_tool::FramePlan padded = nonbloppy_tool::planFrames(parseFramePattern(mDir + pattern, "IN"),
                                                                            std::nullopt);
        ASSERT_EQ(padded.frames.size(), 1u) << pattern;
        EXPECT_EQ(padded.frames[0].input, mDir + "/g_0001.vtk");
    }
}

TEST_F(FindFramesTest, TwoNamesForOneFrameIsAnErrorWhenThatFrameIsPlanned)
{
    touch("f_1.vtk");
    touch("f_01.vtk");
    touch("f_2.vtk");
    const FramePattern braces = parseFramePattern(mDir + "/f_{}.vtk", "IN");
    const std::string message = mDir + "/f_01.vtk and " + mDir + "/f_1.vtk are both frame 1";
    EXPECT_EQ(errorOf([&] { nonbloppy_tool::planFrames(braces, std::nullopt); }), message);
    EXPECT_EQ(errorOf([&] { nonbloppy_tool::planFrames(braces, parseFrameList("1-2")); }), message);
    // A leftover file of frame 1 used to stop '--frames 2' as well: every farm task failed.
    const nonbloppy_tool::FramePlan two = nonbloppy_tool::planFrames(braces, parseFrameList("2"));
    ASSERT_EQ(two.frames.size(), 1u);
    EXPECT_EQ(two.frames[0].input, mDir + "/f_2.vtk");
}

TEST_F(FindFramesTest, PlaceholdersInDirectoriesArePartOfTheirNames)
{
    // A shot directory "take#2" or "50%done" made every path in it a pattern: a single
    // file there could not be meshed, nor a sequence of frames in it.
    fs::create_directories(mDir + "/take#2");
    std::ofstream(mDir + "/take#2/f_7.vtk") << "x";
    const FramePattern inTake = parseFramePattern(mDir + "/take#2/f_{}.vtk", "IN");
    EXPECT_EQ(inTake.kind(), FramePattern::Kind::Braces);
    const std::vector<Frame> frames = nonbloppy_tool::findFrames(inTake);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(frames[0].input, mDir + "/take#2/f_7.vtk");
    EXPECT_EQ(inTake.path(8), mDir + "/take#2/f_8.vtk");
    EXPECT_FALSE(parseFramePattern("take#2/single.ply", "--output").hasPlaceholder());
    EXPECT_FALSE(parseFramePattern("50%d/{}x/m.obj", "--output").hasPlaceholder());
    EXPECT_EQ(parseFramePattern("a_{}/b_##/m_%03d.obj", "--output").width(), 3);

    // Only a directory spelling one: no sequence of directories is taken (the command
    // refuses it when no such file exists).
    EXPECT_TRUE(nonbloppy_tool::placeholderInDirectory("take_{}/fluid.vtk"));
    EXPECT_TRUE(nonbloppy_tool::placeholderInDirectory("/a/f_%04d/b/fluid.vtk"));
    EXPECT_FALSE(nonbloppy_tool::placeholderInDirectory("take_2/fluid_{}.vtk"));
    EXPECT_FALSE(nonbloppy_tool::placeholderInDirectory("fluid_#.vtk"));

    // A frame's path keeps the directory as typed: "take#2//f_{}.vtk" named frame 7
    // ".../take#2/f_7.vtk" in a sequence, recorded so in its .vdb, and as typed alone.
    const FramePattern doubled = parseFramePattern(mDir + "/take#2//f_{}.vtk", "IN");
    ASSERT_EQ(nonbloppy_tool::findFrames(doubled).size(), 1u);
    EXPECT_EQ(nonbloppy_tool::findFrames(doubled)[0].input, mDir + "/take#2//f_7.vtk");
    EXPECT_EQ(doubled.directoryPrefix(), mDir + "/take#2//");
    EXPECT_EQ(parseFramePattern("f_{}.vtk", "IN").directoryPrefix(), "");

    const FramePattern missing = parseFramePattern(mDir + "/nowhere/f_{}.vtk", "IN");
    EXPECT_EQ(errorOf([&] { nonbloppy_tool::findFrames(missing); }),
              "cannot read directory " + mDir + "/nowhere: No such file or directory");
}

} // namespace

TEST(FormatBytesTest, PowersOf1024NamedSoAndNoExponents)
{
    // "-v" memory lines said "MB" for MiB and printed 1023.6 KiB as "1.02e+03 KB".
    using nonbloppy_tool::formatBytes;
    EXPECT_EQ(formatBytes(512), "512 B");
    EXPECT_EQ(formatBytes(1536), "1.5 KiB");
    EXPECT_EQ(formatBytes(1047552), "1023 KiB");
    EXPECT_EQ(formatBytes(1048200), "1 MiB");  // 1023.6 KiB
    EXPECT_EQ(formatBytes(1048576), "1 MiB");
    EXPECT_EQ(formatBytes(119345152), "114 MiB");
    EXPECT_EQ(formatBytes(uint64_t(5) << 30), "5 GiB");
}
