// SPDX-License-Identifier: Apache-2.0
/// @file Commands.h
/// @brief The subcommands of the `nonbloppy` tool (in the manner of pbrt's imgtool: one
///        set-up function that declares a command's options, one function that runs it).
///
/// Every run function returns the process exit code and reports failures by throwing:
/// main() prints what() as the single line "nonbloppy: <message>" and exits with 2 for a
/// UsageError, 1 for any other error.

#ifndef NONBLOPPY_TOOL_COMMANDS_H
#define NONBLOPPY_TOOL_COMMANDS_H

#include "UsageError.h"

#include <nonbloppy/Particles.h>

#include <CLI/CLI.hpp>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

namespace nonbloppy_tool {

/// Help headings, shared by every command, in the order splashsurf uses.
constexpr const char* kGroupInputOutput = "Input/output";
constexpr const char* kGroupNumerical = "Numerical parameters";
constexpr const char* kGroupAdvanced = "Advanced";
constexpr const char* kGroupDebug = "Debug";

/// Exit status after SIGINT/SIGTERM (128 + SIGINT, as shells report it).
constexpr int kExitInterrupted = 130;


/// One subcommand: its CLI11 sub-app (options, help) and what runs it after parsing.
struct Command
{
    CLI::App* app = nullptr;
    std::function<int()> run;
};

/// Declare `nonbloppy mesh` on @a parent.
Command setupMeshCommand(CLI::App& parent);
/// Declare `nonbloppy inspect` on @a parent.
Command setupInspectCommand(CLI::App& parent);
/// Declare `nonbloppy convert` on @a parent.
Command setupConvertCommand(CLI::App& parent);

/// Where a command's warnings go: stderr, a whole line at a time. While a sequence's progress
/// bar stands on the terminal, runBatch() routes them past it (route()): the bar is erased,
/// under the bar's own lock, before each line, so that neither runs into the other.
/// Thread-safe.
class WarningPrinter
{
public:
    /// Print "nonbloppy: warning: " + @a text as one line.
    void warn(const std::string& text) const
    {
        const std::string line = "nonbloppy: warning: " + text + "\n";
        std::lock_guard<std::mutex> lock(mMutex);
        if (mRoute) {
            mRoute(line);
        } else {
            std::cerr << line << std::flush;
        }
    }
    /// Hand every line to @a print from now on; an empty function restores stderr.
    void route(std::function<void(const std::string&)> print)
    {
        std::lock_guard<std::mutex> lock(mMutex);
        mRoute = std::move(print);
    }

private:
    mutable std::mutex mMutex;
    std::function<void(const std::string&)> mRoute;
};

/// Builds one warning and hands it to a WarningPrinter when it goes out of scope:
/// `WarningLine(printer) << "the particles reach " << far;`.
class WarningLine
{
public:
    explicit WarningLine(const WarningPrinter& printer) : mPrinter(printer) {}
    ~WarningLine() { mPrinter.warn(mText.str()); }
    WarningLine(const WarningLine&) = delete;
    WarningLine& operator=(const WarningLine&) = delete;
    template<typename T>
    WarningLine& operator<<(const T& value)
    {
        mText << value;
        return *this;
    }

private:
    const WarningPrinter& mPrinter;
    std::ostringstream mText;
};

/// Warn on stderr, one line per attribute, where a writer renamed one for @a path's format
/// (@a original[i] written as @a written[i]; an empty written name is an attribute dropped,
/// which the caller reports itself): "nonbloppy: warning: attribute 'a b' is written to
/// out.ply as 'a_b_2'". Defined in main.cc.
void warnRenamedAttributes(const std::vector<std::string>& original, const std::vector<std::string>& written,
                           const std::string& path, const WarningPrinter& printer);

/// Whether @a item of ParticleSet::skipped is what makes a file a mesh: a PLY's faces, a
/// legacy VTK's polygons or triangle strips, a VTK PolyData's Polys or Strips, as the
/// readers name them (the CLI tests check both spellings).
inline bool isSurfaceSkipped(const std::string& item)
{
    return item == "element 'face'" || item == "POLYGONS section" || item == "TRIANGLE_STRIPS section" ||
           item == "Polys section" || item == "Strips section";
}

/// Whether @a item of ParticleSet::skipped holds particles left out: a .vdb's point grid
/// after the first ("point grid 'B'"), which alone is read.
inline bool isPointGridSkipped(const std::string& item)
{
    return item.rfind("point grid '", 0) == 0;
}

/// @a particles.skipped as one list: "group 'splash', string attribute 'name'"; without
/// the mesh's faces (isSurfaceSkipped()) unless @a withSurfaces.
inline std::string joinedSkipped(const nonbloppy::ParticleSet& particles, bool withSurfaces = true)
{
    std::string list;
    for (const std::string& item : particles.skipped) {
        if (withSurfaces || !isSurfaceSkipped(item)) list += (list.empty() ? "" : ", ") + item;
    }
    return list;
}

/// "1 frame", "0 frames", "2 frames": @a count and @a noun, made plural unless it is one.
inline std::string counted(size_t count, const std::string& noun)
{
    return std::to_string(count) + " " + noun + (count == 1 ? "" : "s");
}

/// Warn on stderr that attribute @a name holds integers past 2^53, which @a path stores
/// as doubles, rounded (nonbloppy::roundedAttributes() tells which): "nonbloppy: warning:
/// attribute 'id' holds integers past 2^53, which out.ply stores as doubles, rounded (PLY has
/// no 64-bit integers); write .vtk to keep them exact". Defined in main.cc.
void warnRounded(const std::string& name, const std::string& path, const WarningPrinter& printer);

/// @throw UsageError("<@a name> needs a file name, got ''") if @a path is empty, say a shell
///        variable left unset: "cannot open : No such file or directory" named nothing, and
///        an empty --vdb wrote no grid without a word.
inline void requireFileName(const std::string& path, const std::string& name)
{
    if (path.empty()) throw UsageError(name + " needs a file name, got ''");
}

/// The extension of @a path's last component with its dot, lower-cased (".vtk"), or "".
inline std::string lowerExtension(const std::string& path)
{
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

/// A number as a person reads it: shortest of %g with 6 significant digits ("0.05", "1.5").
/// This is also how the library spells numbers in its parameter errors.
inline std::string formatNumber(double value)
{
    if (std::isnan(value)) return "nan";  // whatever its sign bit ("-nan")
    std::ostringstream out;
    out << value;
    return out.str();
}

/// The value @a v as the shortest text that reads back to it: "24388", "-0.125", "3.4e+38".
template<typename T>
std::string shortestText(T v)
{
    char digits[48];
    return std::string(digits, std::to_chars(digits, digits + sizeof(digits), v).ptr);
}

/// A point's coordinates as T, each as the shortest text that reads back as it:
/// "(1000000.7, 0.25, -3)". T is float for particle positions (what the files hold) and double
/// for numbers a user gave. formatNumber()'s six digits dropped a box's width far from the
/// origin ("(1e+06, ...) -> (1e+06, ...)" for a cube 0.7 wide at x = 1e6; hostile-input audit).
template<typename T>
std::string formatPoint(const openvdb::Vec3d& p)
{
    return "(" + shortestText(T(p[0])) + ", " + shortestText(T(p[1])) + ", " + shortestText(T(p[2])) + ")";
}

/// A count with a K/M/G suffix, as vdb_print prints voxel counts ("24.4K", "1.21M").
inline std::string formatCount(uint64_t n)
{
    char buffer[32];
    if (n < 1000) std::snprintf(buffer, sizeof(buffer), "%llu", static_cast<unsigned long long>(n));
    else if (n < 1000000) std::snprintf(buffer, sizeof(buffer), "%.3gK", double(n) / 1e3);
    else if (n < 1000000000) std::snprintf(buffer, sizeof(buffer), "%.3gM", double(n) / 1e6);
    else std::snprintf(buffer, sizeof(buffer), "%.3gG", double(n) / 1e9);
    return buffer;
}

/// A byte count in KiB/MiB/GiB ("28.8 MiB", "1023 KiB"): powers of 1024, named so (they
/// read "MB", and 1023.6 KiB printed as "1.02e+03 KB").
inline std::string formatBytes(uint64_t n)
{
    if (n < 1024) return std::to_string(n) + " B";
    const char* units[] = {"KiB", "MiB", "GiB", "TiB"};
    double value = double(n) / 1024.0;
    size_t unit = 0;
    while (value >= 1023.5 && unit + 1 < sizeof(units) / sizeof(units[0])) {
        value /= 1024.0;
        ++unit;
    }
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), value >= 99.95 ? "%.0f %s" : "%.3g %s", value, units[unit]);
    return buffer;
}

} // namespace nonbloppy_tool

#endif // NONBLOPPY_TOOL_COMMANDS_H
