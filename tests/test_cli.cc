// SPDX-License-Identifier: Apache-2.0
/// @file test_cli.cc
/// @brief Runs the built `nonbloppy` tool (NONBLOPPY_CLI_PATH) as a user would: outputs,
///        `inspect`, one-line errors with exact messages, no files left after a failure,
///        thread-count independence.

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "../src/AtomicFile.h"
#include "CliTestUtil.h"
#include "TestUtil.h"  // NONBLOPPY_TEST_ASAN

#include <nonbloppy/CgroupLimits.h>
#include <nonbloppy/CropParticles.h>
#include <nonbloppy/EstimateParameters.h>
#include <nonbloppy/ReadMesh.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/ReadVdb.h>
#include <nonbloppy/WriteParticles.h>
#include <nonbloppy/WriteVdb.h>
#include <openvdb/openvdb.h>
#include <openvdb/version.h>
#include <tbb/info.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using namespace nonbloppy_test;

const std::string kData = NONBLOPPY_TEST_DATA_DIR;
const std::string kCube = kData + "/cube_2366_particles.vtk";
const std::string kDamBreak = kData + "/dam_break_frame_23_24389_particles.vtk";

/// Wait (at most 30 s) until process @a pid catches @a signal, as its /proc status tells
/// (SigCgt: the caught signals as a hex mask, signal n at bit n - 1): its handler is installed.
void waitUntilCatches(pid_t pid, int signal)
{
    const auto catches = [&] {
        std::istringstream status(readText("/proc/" + std::to_string(pid) + "/status"));
        for (std::string line; std::getline(status, line);) {
            if (line.rfind("SigCgt:", 0) == 0) return (std::stoull(line.substr(7), nullptr, 16) >> (signal - 1)) & 1;
        }
        return 0ull;
    };
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (!catches() && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
}

class CliTest : public CliFixture
{
protected:
    /// Mesh the cube into out/NAME.obj and out/NAME.vdb; returns the run.
    RunResult meshCube(const std::string& name, const std::string& extra = "") const
    {
        return run("mesh " + quote(kCube) + " -o " + quote(out(name + ".obj")) + " --vdb "
                   + quote(out(name + ".vdb")) + " " + extra);
    }
    std::string writeSparseParticles() const;
    /// The arguments that mesh writeSparseParticles()'s file.
    std::string meshSparseParticles(const std::string& input) const;
    double expectSparseParticlesRefused(const RunResult& r, const std::string& input) const;
};

} // namespace

TEST_F(CliTest, MeshWritesObjAndVdbAndSummary)
{
    const RunResult r = meshCube("cube");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    // Whole rows: the file's name holds "particles" and "2366" too.
    EXPECT_NE(r.out.find("\n  particles            2366\n"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\n  spacing s            0.0498381      (derived)\n"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("volume offset        off            (needs --spacing)"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("smoothing            off            (needs --spacing)"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("region leaves        1024           (default)"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("rasterize density"), std::string::npos) << r.out;
    // Each timing line ends with the cores the stage kept busy, its CPU over wall-clock time.
    EXPECT_NE(r.out.find("timings                      wall             cores\n"), std::string::npos) << r.out;
    const size_t total = r.out.find("\n  total ");
    ASSERT_NE(total, std::string::npos) << r.out;
    double totalSeconds = 0.0, totalCores = 0.0;
    ASSERT_EQ(std::sscanf(r.out.c_str() + total, " total %lf s %lf", &totalSeconds, &totalCores), 2) << r.out;
    EXPECT_GT(totalSeconds, 0.0);
    EXPECT_GT(totalCores, 0.0) << r.out;
    EXPECT_EQ(listDir(dir() + "/out"), (std::vector<std::string>{"cube.obj", "cube.vdb"}));
    EXPECT_GT(fs::file_size(out("cube.obj")), 1000u);
    EXPECT_GT(fs::file_size(out("cube.vdb")), 1000u);
}

TEST_F(CliTest, SpacingTurnsOnVolumeOffsetAndSmoothingAndNoSmoothTurnsItOff)
{
    const RunResult smoothed = meshCube("smoothed", "--spacing 0.05");
    ASSERT_EQ(smoothed.exitCode, 0) << smoothed.err;
    EXPECT_NE(smoothed.out.find("volume offset        convex         (N*s^3, --spacing given)"), std::string::npos)
        << smoothed.out;
    EXPECT_NE(smoothed.out.find("smoothing            on             (with the volume offset)"), std::string::npos)
        << smoothed.out;
    EXPECT_NE(smoothed.out.find("smooth surface"), std::string::npos) << smoothed.out;  // its timing
    const RunResult plain = meshCube("plain", "--spacing 0.05 --no-smooth");
    ASSERT_EQ(plain.exitCode, 0) << plain.err;
    EXPECT_NE(plain.out.find("smoothing            off            (--no-smooth)"), std::string::npos) << plain.out;
    EXPECT_EQ(plain.out.find("smooth surface"), std::string::npos) << plain.out;
    // Same polygons, other vertex positions.
    const std::string smoothedObj = readText(out("smoothed.obj")), plainObj = readText(out("plain.obj"));
    EXPECT_EQ(count(smoothedObj, "\nf "), count(plainObj, "\nf "));
    EXPECT_GT(count(plainObj, "\nf "), 1000u);
    EXPECT_NE(smoothedObj, plainObj);
}

TEST_F(CliTest, TheSummaryCountsPolygonsAsInspectDoes)
{
    const RunResult r = meshCube("quads", "--quads");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string inspected = run("inspect " + quote(out("quads.obj"))).out;
    const size_t at = inspected.find("  faces            ");
    ASSERT_NE(at, std::string::npos) << inspected;
    const std::string counts = inspected.substr(at + 19, inspected.find('\n', at) - at - 19);  // "N (T triangles, Q quads)"
    EXPECT_NE(r.out.find("  polygons             " + counts.substr(0, counts.find(' ')) + " "), std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find(counts.substr(counts.find('('))), std::string::npos) << r.out << "\n" << counts;
}

TEST_F(CliTest, QuietPrintsNothing)
{
    const RunResult r = meshCube("cube", "--quiet");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_TRUE(r.err.empty()) << r.err;
}

TEST_F(CliTest, WarnsWhenRelaxationIsTooStrongForTheCalibration)
{
    // c = 0.5, t = 4 would need the surface to start farther out than the calibration
    // allows (CorrectSurface.h): the faces end inside, and the user is told once.
    const RunResult strong = meshCube("strong", "-q --blend 0.5 --iterations 4");
    ASSERT_EQ(strong.exitCode, 0) << strong.err;
    EXPECT_EQ(strong.err, "nonbloppy: warning: --blend 0.5 --iterations 4 relax too strongly for --threshold "
                          "to be calibrated: flat faces end inside the particles; lower --blend or "
                          "--iterations, or give --spacing to correct the volume\n");
    // With --spacing given the volume is corrected already: not advised again.
    const RunResult spaced = meshCube("spaced", "-q --blend 0.5 --iterations 4 --spacing 0.05");
    ASSERT_EQ(spaced.exitCode, 0) << spaced.err;
    EXPECT_EQ(spaced.err, "nonbloppy: warning: --blend 0.5 --iterations 4 relax too strongly for --threshold "
                          "to be calibrated: flat faces end inside the particles; lower --blend or --iterations\n");
    // A threshold of the user's own is not calibrated: nothing to warn about.
    const RunResult given = meshCube("given", "-q --blend 0.5 --iterations 4 --threshold 3");
    ASSERT_EQ(given.exitCode, 0) << given.err;
    EXPECT_TRUE(given.err.empty()) << given.err;
}

/// A memory check's refusal: exit 1, stderr one line from @a head to @a tail, what the process
/// can still take between them (it depends on the machine), and nothing in @a outDir.
/// Returns stderr.
std::string expectMemoryRefusal(const RunResult& r, const std::string& head, const std::string& tail,
                                const std::string& outDir)
{
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err.rfind(head, 0), 0u) << r.err;
    EXPECT_GT(r.err.size(), head.size() + tail.size());
    if (r.err.size() >= tail.size()) EXPECT_EQ(r.err.substr(r.err.size() - tail.size()), tail) << r.err;
    EXPECT_TRUE(listDir(outDir).empty());
    return r.err;
}

/// 4096 particles 3 apart, in.../sparse.csv, whose density grid at meshSparseParticles()'s
/// parameters takes 5.57 GB to 11.1 GB. Returns the file's path.
std::string CliTest::writeSparseParticles() const
{
    std::string csv = "x,y,z\n";
    for (int i = 0; i < 16 * 16 * 16; ++i) {
        csv += std::to_string(3 * (i % 16)) + "," + std::to_string(3 * (i / 16 % 16)) + "," + std::to_string(3 * (i / 256))
               + "\n";
    }
    const std::string input = in("sparse.csv");
    writeText(input, csv);
    return input;
}

std::string CliTest::meshSparseParticles(const std::string& input) const
{
    return "mesh " + quote(input) + " -o " + quote(out("s.ply")) + " --radius 1 --voxel-size 0.0325 --threshold 2"
           " --threads 2";
}

/// The refusal of meshSparseParticles(): the message as the memory checks word it, nothing
/// written. Returns what it says the process can still take, in GB (0 where unreadable).
double CliTest::expectSparseParticlesRefused(const RunResult& r, const std::string& input) const
{
    const std::string head = "nonbloppy: " + input + ": the density grid (up to 5088448 leaves of 8^3 voxels) of "
                             "these particles at --voxel-size 0.0325 and --radius 1 would take 5.57 GB to 11.1 GB, more "
                             "than the ";
    const std::string tail = " this process can still take: give a larger --voxel-size or a smaller --radius\n";
    const std::string message = expectMemoryRefusal(r, head, tail, dir() + "/out");
    if (message.rfind(head, 0) != 0 || message.size() <= head.size() + tail.size()) return 0.0;
    size_t digits = 0;
    double headroom = std::stod(message.substr(head.size()), &digits);  // in GB, or MB below 1 GB
    const std::string unit = message.substr(head.size() + digits, 3);
    if (unit == " MB") headroom /= 1000.0;
    else EXPECT_EQ(unit, " GB") << message;
    return headroom;
}

TEST_F(CliTest, ADensityGridLargerThanTheMemoryIsRefusedBeforeItIsAllocated)
{
#if defined(NONBLOPPY_TEST_ASAN)
    GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit this test sets";
#else
    // 4096 particles 3 apart, each with a sphere of 62 voxels across: about 6 GB of density
    // leaves. Under a 1.5 GB limit the run ended in "out of memory" (bug hunt); on a
    // smaller farm node, in the kernel's OOM killer.
    const std::string input = writeSparseParticles();
    const RunResult r = runWithAddressLimit(1500000, meshSparseParticles(input));
    // What the process can still take is the limit less what it holds by then (libraries,
    // thread stacks, the particles and their index): below 1.54 GB. Two threads: each more
    // takes about 70 MB of address space (its stack and malloc arena), so the default count
    // on a machine of 12 cores would leave less than the 0.5 GB checked below.
    const double headroom = expectSparseParticlesRefused(r, input);
    EXPECT_GT(headroom, 0.5);
    EXPECT_LT(headroom, 1.54);
#endif
}

TEST_F(CliTest, RunningOutOfMemoryNamesTheStageAndTheFile)
{
#if defined(NONBLOPPY_TEST_ASAN)
    GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit this test sets";
#else
    // 4M particles under limits of address space from 340 to 450 MB: past the memory checks,
    // some allocation fails (on this machine in the estimate, the rasterization or the
    // extraction, depending on the limit). The message said only "out of memory"; it names
    // the stage (or, while reading, the file) and the input. And no stage may crash instead:
    // the index build did, exit 139, at 340 MB (see runIsolatedFromCancellation()).
    // Where each limit ends is not fixed: 450 MB is about 20 MB short of what the run needs,
    // and a run's address space moves with thread timing. So a limit may also be met by the
    // memory checks' refusal, or by the whole run; at least one must name a stage. Two
    // threads: each thread's malloc arena takes address space of its own.
    std::string csv = "x,y,z\n";
    csv.reserve(size_t(90) << 20);
    char row[64];
    for (int i = 0; i < 4000000; ++i) {
        csv.append(row, size_t(std::snprintf(row, sizeof(row), "%.4f,%.4f,%.4f\n", (i % 200) * 0.05,
                                             (i / 200 % 200) * 0.05, (i / 40000) * 0.05)));
    }
    const std::string input = in("many.csv");
    writeText(input, csv);
    csv = std::string();
    int stagesNamed = 0;
    for (const size_t kilobytes : {340000, 380000, 400000, 450000}) {
        SCOPED_TRACE(kilobytes);
        const RunResult r =
            runWithAddressLimit(kilobytes, "mesh " + quote(input) + " -q --threads 2 -o " + quote(out("m.ply")));
        if (r.exitCode == 0) {
            EXPECT_EQ(r.err, "");
            EXPECT_EQ(listDir(dir() + "/out"), std::vector<std::string>{"m.ply"});
            std::remove(out("m.ply").c_str());
            continue;
        }
        EXPECT_EQ(r.exitCode, 1);
        const std::string inStage = "nonbloppy: out of memory in stage '", meshing = "' meshing " + input + "\n";
        const std::string reading = "nonbloppy: out of memory while reading the particles (" + input + ")\n";
        const std::string refusedHead = "nonbloppy: " + input + ": ";
        const std::string refusedTail = " this process can still take: give a larger --voxel-size or a smaller --radius\n";
        const bool oneLine = std::count(r.err.begin(), r.err.end(), '\n') == 1;
        const auto endsWith = [&](const std::string& tail) {
            return r.err.size() >= tail.size() && r.err.compare(r.err.size() - tail.size(), tail.size(), tail) == 0;
        };
        const bool namesStage = r.err.rfind(inStage, 0) == 0 && r.err.size() > inStage.size() + meshing.size()
                                && endsWith(meshing) && oneLine;
        const bool refused = r.err.rfind(refusedHead, 0) == 0 && endsWith(refusedTail) && oneLine;
        stagesNamed += namesStage ? 1 : 0;
        EXPECT_TRUE(namesStage || refused || r.err == reading) << r.err;
        EXPECT_TRUE(listDir(dir() + "/out").empty()) << "output files left behind";
    }
    EXPECT_GE(stagesNamed, 1);
#endif
}

TEST_F(CliTest, ASmoothingLargerThanTheMemoryIsRefusedBeforeItIsAllocated)
{
#if defined(NONBLOPPY_TEST_ASAN)
    GTEST_SKIP() << "AddressSanitizer reserves more address space than the limit this test sets";
#else
    // A sheet of 500 x 500 particles one layer thick: 2.0M polygons, whose smoothing takes
    // more memory than the density grid, the mesh and the relaxation before it (146 MB of
    // scratch on top of a 141 MB peak). Under a 550 MB limit of address space every stage
    // before it fits (from about 430 MB: "out of memory" below) and the smoothing does not
    // (up to 700-720 MB, where a build without the check fails too); without the check the
    // kernel's OOM killer ends such a run on a farm node with nothing said.
    std::string xyz;
    for (int i = 0; i < 500; ++i) {
        for (int j = 0; j < 500; ++j) {
            const float position[3] = {float(i), float(j), 0.0f};
            xyz.append(reinterpret_cast<const char*>(position), sizeof(position));
        }
    }
    const std::string input = in("sheet.xyz");
    writeText(input, xyz);
    const std::string args = "mesh " + quote(input) + " -o " + quote(out("sheet.ply")) + " --spacing 1 --threads 2 -q";
    expectMemoryRefusal(runWithAddressLimit(550000, args),
                        "nonbloppy: " + input + ": smoothing the surface (2023982 polygons) would take another ",
                        " this process can still take: give --no-smooth to skip it\n", dir() + "/out");
    // The same sheet without the smoothing fits.
    const RunResult unsmoothed = runWithAddressLimit(550000, args + " --no-smooth");
    EXPECT_EQ(unsmoothed.exitCode, 0) << unsmoothed.err;
#endif
}

TEST_F(CliTest, VerbosePrintsStagesOnStderr)
{
    const RunResult r = meshCube("cube", "-v");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.err.find("read particles"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("write mesh"), std::string::npos) << r.err;
}

TEST_F(CliTest, GivenParametersAreMarkedGiven)
{
    const RunResult r = meshCube("cube", "--radius 0.1 -c 0.5 -t 1");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* row : {"\n  radius r_e           0.1            (given)\n",
                            "\n  threshold r_0        3.18499        (derived)\n",
                            "\n  blend c              0.5            (given)\n",
                            "\n  iterations t         1              (given)\n",
                            "\n  adaptivity           0              (default)\n"}) {
        EXPECT_NE(r.out.find(row), std::string::npos) << row << r.out;
    }
}

TEST_F(CliTest, InspectMeshIsClosedManifoldWithPositiveVolume)
{
    ASSERT_EQ(meshCube("cube", "-q").exitCode, 0);
    const RunResult r = run("inspect --json " + quote(out("cube.obj")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("\"closed\": true"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\"manifold\": true"), std::string::npos) << r.out;
    // The counts are the file's own: one "v " line per vertex, one "f " line per face.
    const std::string obj = readText(out("cube.obj"));
    ASSERT_EQ(obj.rfind("# ", 0), 0u);  // so every "v " and "f " line follows a newline
    EXPECT_EQ(jsonNumber(r.out, "vertices"), double(count(obj, "\nv "))) << r.out;
    EXPECT_EQ(jsonNumber(r.out, "faces"), double(count(obj, "\nf "))) << r.out;
    EXPECT_GT(jsonNumber(r.out, "area"), 0.0) << r.out;
    EXPECT_NE(r.out.find("\"attributes\": []"), std::string::npos) << r.out;  // OBJ holds none
    const double volume = jsonNumber(r.out, "volume");
    // The calibrated r_0 ends flat faces s/2 outside the outer layer, so the cube encloses
    // N s³ (s = 0.0498381, the estimate), less what relaxation takes from edges and corners:
    // 0.25% less, measured.
    const double expected = 2366 * std::pow(0.0498381, 3);  // 0.29289
    EXPECT_NEAR(volume, expected, 0.005 * expected) << r.out;
}

TEST_F(CliTest, AdaptivityMergesFacesAndKeepsTheMeshClosed)
{
    // --adaptivity reaches buildSurface() through the CLI: the cube's flat faces merge into
    // larger triangles (5952 instead of 12244, measured), the mesh stays closed and
    // manifold, and its volume moves by less than 1% (0.45%, measured).
    ASSERT_EQ(meshCube("full", "-q").exitCode, 0);
    const RunResult adaptive = meshCube("adaptive", "--adaptivity 0.5");
    ASSERT_EQ(adaptive.exitCode, 0) << adaptive.err;
    EXPECT_NE(adaptive.out.find("\n  adaptivity           0.5            (given)\n"), std::string::npos) << adaptive.out;
    const RunResult full = run("inspect --json " + quote(out("full.obj")));
    const RunResult merged = run("inspect --json " + quote(out("adaptive.obj")));
    ASSERT_EQ(full.exitCode, 0) << full.err;
    ASSERT_EQ(merged.exitCode, 0) << merged.err;
    EXPECT_LT(jsonNumber(merged.out, "faces"), 0.6 * jsonNumber(full.out, "faces")) << merged.out << full.out;
    EXPECT_NE(merged.out.find("\"closed\": true"), std::string::npos) << merged.out;
    EXPECT_NE(merged.out.find("\"manifold\": true"), std::string::npos) << merged.out;
    EXPECT_NEAR(jsonNumber(merged.out, "volume"), jsonNumber(full.out, "volume"), 0.01 * jsonNumber(full.out, "volume"));
}

TEST_F(CliTest, InspectSaysWhyAnOpenOrEmptyMeshIsNotManifold)
{
    // "manifold" includes "closed": an open mesh with no bad edge is still not manifold.
    writeText(out("triangle.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    RunResult r = run("inspect " + quote(out("triangle.obj")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("  closed           no (3 boundary edges)\n"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("  manifold         no (0 non-manifold, 0 inconsistently oriented edges; not closed)\n"),
              std::string::npos) << r.out;
    writeText(out("empty.obj"), "");
    r = run("inspect " + quote(out("empty.obj")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("  closed           no (no faces)\n  manifold         no (no faces)\n"), std::string::npos)
        << r.out;
}

TEST_F(CliTest, InspectCountsZeroAreaFacesAndNonFiniteVertices)
{
    // A triangle with a corner repeated is closed and manifold by its edges; a NaN vertex
    // gave area "nan" with no word why.
    writeText(out("degenerate.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 nan\nf 1 1 2\n");
    RunResult r = run("inspect " + quote(out("degenerate.obj")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("  vertices         4, 2 unused, 1 not finite\n"
                         "  faces            1 (1 triangle, 0 quads, 1 of zero area)\n"), std::string::npos) << r.out;
    r = run("inspect --json " + quote(out("degenerate.obj")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(jsonNumber(r.out, "non_finite_vertices"), 1.0) << r.out;
    EXPECT_EQ(jsonNumber(r.out, "zero_area_faces"), 1.0) << r.out;
}

TEST_F(CliTest, InspectListsAMeshsAttributesOnlyWhenTheyCanBeRead)
{
    // A mesh's vertex attributes are read as particles, which refuse a NaN vertex that the
    // mesh reader takes: then they are unknown, not "none".
    const std::string header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nproperty float temp\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n";
    writeText(out("fine.ply"), header + "0 0 0 1\n1 0 0 2\n0 1 0 3\n3 0 1 2\n");
    writeText(out("nan.ply"), header + "0 0 0 1\n1 0 0 2\nnan 1 0 3\n3 0 1 2\n");
    RunResult r = run("inspect " + quote(out("fine.ply")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("\n  attributes       temp  float32  1 .. 3\n"), std::string::npos) << r.out;
    r = run("inspect " + quote(out("nan.ply")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("\n  attributes       - (the particle readers refuse this file)\n"), std::string::npos) << r.out;
    r = run("inspect --json " + quote(out("nan.ply")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("\"attributes\": null"), std::string::npos) << r.out;
    // A VTK mesh's normals are not an attribute, whatever their array's name.
    writeText(out("normals.vtk"), "# vtk DataFile Version 3.0\nm\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n"
                                  "0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 2\nPOINT_DATA 3\nVECTORS vel float\n"
                                  "1 2 3 4 5 6 7 8 9\nNORMALS Normals float\n0 0 2 0 0 1 0 0.5 1\n");
    r = run("inspect " + quote(out("normals.vtk")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("(with normals)"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\n  attributes       vel  float32 x3  x 1 .. 7, y 2 .. 8, z 3 .. 9\n"), std::string::npos)
        << r.out;
    EXPECT_EQ(r.out.find("Normals"), std::string::npos) << r.out;
}

TEST_F(CliTest, InspectVdbListsDensityGrid)
{
    ASSERT_EQ(meshCube("cube", "-q").exitCode, 0);
    const RunResult text = run("inspect " + quote(out("cube.vdb")));
    ASSERT_EQ(text.exitCode, 0) << text.err;
    EXPECT_NE(text.out.find("density  float"), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("source_file: " + kCube), std::string::npos) << text.out;

    const RunResult json = run("inspect --json " + quote(out("cube.vdb")));
    ASSERT_EQ(json.exitCode, 0) << json.err;
    EXPECT_NE(json.out.find("\"grids\": ["), std::string::npos) << json.out;
    EXPECT_NE(json.out.find("\"name\": \"density\""), std::string::npos) << json.out;
    const nonbloppy::VdbFileContents cache = nonbloppy::readVdbFile(out("cube.vdb"));
    ASSERT_EQ(cache.grids.size(), 1u);
    EXPECT_EQ(jsonNumber(json.out, "active_voxels"), double(cache.grids[0]->activeVoxelCount())) << json.out;
}

TEST_F(CliTest, InspectShowsNanAndInfMetadataAsSuch)
{
    // Text said "null", JSON's word for them, which names no number.
    openvdb::initialize();
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
    grid->setName("g");
    grid->insertMeta("not_a_number", openvdb::DoubleMetadata(std::nan("")));
    grid->insertMeta("too_far", openvdb::FloatMetadata(-std::numeric_limits<float>::infinity()));
    nonbloppy::writeVdb({grid}, out("meta.vdb"));
    const RunResult text = run("inspect " + quote(out("meta.vdb")));
    ASSERT_EQ(text.exitCode, 0) << text.err;
    EXPECT_NE(text.out.find("    not_a_number: nan\n"), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("    too_far: -inf\n"), std::string::npos) << text.out;
    const nlohmann::json json = nlohmann::json::parse(run("inspect --json " + quote(out("meta.vdb"))).out);
    EXPECT_TRUE(json["grids"][0]["metadata"]["not_a_number"].is_null()) << json.dump();
}

TEST_F(CliTest, InspectParticleFile)
{
    const RunResult json = run("inspect --json " + quote(kCube));
    ASSERT_EQ(json.exitCode, 0) << json.err;
    EXPECT_EQ(jsonNumber(json.out, "particles"), 2366.0) << json.out;
    // The spacing mesh estimates for its summary (MeshWritesObjAndVdbAndSummary), in full.
    const nonbloppy::ParticleSet cube = nonbloppy::readParticles(kCube);
    EXPECT_EQ(jsonNumber(json.out, "spacing"), nonbloppy::estimateSpacing(cube.positions)) << json.out;
    EXPECT_NEAR(jsonNumber(json.out, "spacing"), 0.0498381, 5e-8) << json.out;
    // The bounding box is the particles' own, to the float.
    openvdb::Vec3f low(std::numeric_limits<float>::infinity()), high(-std::numeric_limits<float>::infinity());
    for (const openvdb::Vec3f& p : cube.positions) {
        low = openvdb::math::minComponent(low, p);
        high = openvdb::math::maxComponent(high, p);
    }
    const nlohmann::json document = nlohmann::json::parse(json.out);
    for (int axis = 0; axis < 3; ++axis) {
        EXPECT_EQ(document["bbox"]["min"][axis].get<float>(), low[axis]) << axis;
        EXPECT_EQ(document["bbox"]["max"][axis].get<float>(), high[axis]) << axis;
    }

    const RunResult text = run("inspect " + quote(kDamBreak));
    ASSERT_EQ(text.exitCode, 0) << text.err;
    // Whole rows: the file's name holds "24389" too.
    EXPECT_NE(text.out.find("\n  particles        24389\n"), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("\n  attributes       id  uint32  0 .. 24388\n"
                            "                   velocity  float32 x3  x -2.9102397 .. 4.807553, y -3.0431576 .. 8.40207, "
                            "z -1.9850667 .. 2.7985563\n"),
              std::string::npos)
        << text.out;
    // Those ranges are the file's own, to the float (the JSON report's, against the reader).
    const nonbloppy::ParticleSet dam = nonbloppy::readParticles(kDamBreak);
    const nonbloppy::ParticleAttribute* velocity = dam.findAttribute("velocity");
    ASSERT_NE(velocity, nullptr);
    const nlohmann::json damJson =
        nlohmann::json::parse(run("inspect --json " + quote(kDamBreak)).out);
    ASSERT_EQ(damJson["attributes"][1]["name"], "velocity");
    for (int c = 0; c < 3; ++c) {
        double low = velocity->asDouble(0, c), high = low;
        for (size_t n = 1; n < velocity->size(); ++n) {
            low = std::min(low, velocity->asDouble(n, c));
            high = std::max(high, velocity->asDouble(n, c));
        }
        EXPECT_EQ(damJson["attributes"][1]["min"][c].get<float>(), float(low)) << c;
        EXPECT_EQ(damJson["attributes"][1]["max"][c].get<float>(), float(high)) << c;
    }
    EXPECT_EQ(damJson["attributes"][1]["non_finite"], 0);

    // The text's box too, each coordinate as the shortest text of its float: at six digits a
    // box 0.7 wide at x = 1e6 lost its width ("(1e+06, ...) -> (1e+06, ...)").
    std::string far;
    for (int corner = 0; corner < 8; ++corner) {
        far += std::to_string(1e6 + 0.7 * (corner & 1)) + "," + std::to_string(0.7 * ((corner >> 1) & 1)) + ","
               + std::to_string(0.7 * ((corner >> 2) & 1)) + "\n";
    }
    writeText(in("far.csv"), "x,y,z\n" + far);
    const RunResult farText = run("inspect " + quote(in("far.csv")));
    ASSERT_EQ(farText.exitCode, 0) << farText.err;
    EXPECT_NE(farText.out.find("\n  bounding box     (1e+06, 0, 0) -> (1000000.7, 0.7, 0.7)\n"), std::string::npos)
        << farText.out;
}

TEST_F(CliTest, InspectGivesEachAttributesRangeExactlyAndCountsValuesThatAreNotFinite)
{
    // A cache from a simulation that blew up holds NaN velocities; ids past 2^53 and the
    // ends of the 64-bit ranges must come out as they are, not rounded through a double.
    nonbloppy::ParticleSet particles;
    particles.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    particles.attributes.push_back(nonbloppy::ParticleAttribute::of(
        "id", 1, std::vector<int64_t>{(int64_t(1) << 53) + 1, std::numeric_limits<int64_t>::min(), 7, -1}));
    particles.attributes.push_back(nonbloppy::ParticleAttribute::of(
        "key", 1, std::vector<uint64_t>{0, std::numeric_limits<uint64_t>::max(), 5, 6}));
    particles.attributes.push_back(nonbloppy::ParticleAttribute::of("flag", 1, std::vector<int8_t>{-128, 3, 127, 0}));
    particles.attributes.push_back(nonbloppy::ParticleAttribute::of(
        "v", 2, std::vector<float>{1.5f, nan, nan, nan, -inf, nan, -0.25f, nan}));
    nonbloppy::writeParticles(particles, in("odd.vtu"));
    const RunResult text = run("inspect " + quote(in("odd.vtu")));
    ASSERT_EQ(text.exitCode, 0) << text.err;
    EXPECT_NE(text.out.find("\n  attributes       id  int64  -9223372036854775808 .. 9007199254740993\n"
                            "                   key  uint64  0 .. 18446744073709551615\n"
                            "                   flag  int8  -128 .. 127\n"
                            "                   v  float32 x2  0 -0.25 .. 1.5, 6 not finite\n"),
              std::string::npos)
        << text.out;
    const RunResult json = run("inspect --json " + quote(in("odd.vtu")));
    ASSERT_EQ(json.exitCode, 0) << json.err;
    const nlohmann::json document = nlohmann::json::parse(json.out);
    const nlohmann::json& attributes = document["attributes"];
    EXPECT_EQ(attributes[0]["min"][0].get<int64_t>(), std::numeric_limits<int64_t>::min());
    EXPECT_EQ(attributes[0]["max"][0].get<int64_t>(), (int64_t(1) << 53) + 1);
    EXPECT_EQ(attributes[1]["max"][0].get<uint64_t>(), std::numeric_limits<uint64_t>::max());
    EXPECT_EQ(attributes[2]["min"][0].get<int>(), -128);
    EXPECT_EQ(attributes[3]["min"][0].get<float>(), -0.25f);
    EXPECT_TRUE(attributes[3]["min"][1].is_null()) << json.out;  // component 1 has no finite value
    EXPECT_TRUE(attributes[3]["max"][1].is_null()) << json.out;
    EXPECT_EQ(attributes[3]["non_finite"].get<int>(), 6);
    EXPECT_EQ(attributes[0]["non_finite"].get<int>(), 0);
    // -0 and +0 are equal, and std::min keeps whichever it met first, which the threads
    // decide: the range is -0 .. 0 in either order.
    writeText(in("zeros1.csv"), "x,y,z,t\n0,0,0,0.0\n1,0,0,-0.0\n");
    writeText(in("zeros2.csv"), "x,y,z,t\n0,0,0,-0.0\n1,0,0,0.0\n");
    for (const char* name : {"zeros1.csv", "zeros2.csv"}) {
        const RunResult zeros = run("inspect " + quote(in(name)));
        EXPECT_NE(zeros.out.find("\n  attributes       t  float64  -0 .. 0\n"), std::string::npos) << zeros.out;
    }
}

TEST_F(CliTest, MeshWarnsOfVerticesWhoseCarriedAttributeIsNotFinite)
{
    // One NaN temperature among 1,000 particles spreads to every vertex within r_e of it:
    // said once, with the count the written mesh holds; the finite attribute is not named.
    std::string csv = "x,y,z,temp,speed\n";
    for (int i = 0; i < 10; ++i) {
        for (int j = 0; j < 10; ++j) {
            for (int k = 0; k < 10; ++k) {
                const bool bad = i == 5 && j == 5 && k == 9;  // on the top face
                csv += std::to_string(0.05 * i) + "," + std::to_string(0.05 * j) + "," + std::to_string(0.05 * k) + ","
                       + (bad ? std::string("nan") : std::to_string(1.0 + 0.1 * i)) + ",2.0\n";
            }
        }
    }
    writeText(in("hot.csv"), csv);
    const RunResult r = run("mesh -q " + quote(in("hot.csv")) + " -o " + quote(out("hot.ply")) + " --attributes all");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const nonbloppy::ParticleSet mesh = nonbloppy::readParticles(out("hot.ply"));
    const nonbloppy::ParticleAttribute* temp = mesh.findAttribute("temp");
    ASSERT_NE(temp, nullptr);
    size_t notFinite = 0;
    for (size_t n = 0; n < temp->size(); ++n) notFinite += !std::isfinite(temp->asDouble(n));
    ASSERT_GT(notFinite, 0u);
    ASSERT_LT(notFinite, mesh.size() / 10);
    EXPECT_EQ(r.err, "nonbloppy: warning: " + std::to_string(notFinite) + " of the " + std::to_string(mesh.size())
                         + " vertices of " + out("hot.ply") + " have a NaN or infinite 'temp': particles of "
                         + in("hot.csv") + " near them hold such values (nonbloppy inspect counts them)\n");
    // Finite values everywhere: no word.
    const RunResult fine = run("mesh -q " + quote(kDamBreak) + " -o "
                               + quote(out("dam.ply")) + " --attributes all");
    ASSERT_EQ(fine.exitCode, 0) << fine.err;
    EXPECT_EQ(fine.err, "");
}

TEST_F(CliTest, InspectJsonIsValidForNamesThatAreNotUtf8)
{
    // A Latin-1 file name ("café" with é as the byte 0xe9) was copied into the JSON as it was:
    // strict parsers refuse it. Well-formed UTF-8 stays; each stray byte becomes U+FFFD.
    const std::string latin1 = in("caf\xe9 \xff.vtk"), utf8 = in("caf\xc3\xa9 \xe5\x90\x8d.vtk");
    fs::copy_file(kCube, latin1);
    fs::copy_file(kCube, utf8);
    for (const auto& [path, expected] : {std::pair<std::string, std::string>{latin1, in("caf\xef\xbf\xbd \xef\xbf\xbd.vtk")},
                                         {utf8, utf8}}) {
        const RunResult r = run("inspect --json " + quote(path));
        ASSERT_EQ(r.exitCode, 0) << r.err;
        nlohmann::json document;
        ASSERT_NO_THROW(document = nlohmann::json::parse(r.out)) << r.out;
        EXPECT_EQ(document["file"].get<std::string>(), expected);
        EXPECT_EQ(document["particles"].get<int>(), 2366);
    }
}

TEST_F(CliTest, VdbPrintReadsTheCache)
{
    if (!fs::exists("/usr/bin/vdb_print")) GTEST_SKIP() << "vdb_print not installed";
    ASSERT_EQ(meshCube("cube", "-q").exitCode, 0);
    const std::string command = "/usr/bin/vdb_print -m " + quote(out("cube.vdb")) + " >"
                                + quote(dir() + "/vdb_print.txt") + " 2>&1";
    const int status = std::system(command.c_str());
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << readText(dir() + "/vdb_print.txt");
    const std::string printed = readText(dir() + "/vdb_print.txt");
    EXPECT_NE(printed.find("density"), std::string::npos) << printed;
    EXPECT_NE(printed.find("effective_radius"), std::string::npos) << printed;
}

/// A cgroup a test makes below this process's own for @a controller, with the limit files
/// @a v1Limits or @a v2Limits (as the hierarchy is v1 or v2) and, if @a child names one, a
/// child without limits of its own, where commands then run. Both go when it does. Its
/// directories are empty where the machine does not let a test make one (not root, a
/// read-only or delegated cgroup file system, no such controller there).
class ScratchCgroup
{
public:
    using Files = std::vector<std::pair<std::string, std::string>>;  // {name, contents}

    ScratchCgroup(nonbloppy::CgroupController controller, const Files& v1Limits, const Files& v2Limits,
                  const std::string& child = "")
    {
        // Where the library looks for limits (CgroupLimits.h): below the suite's cgroup.
        const std::optional<nonbloppy::CgroupLocation> parent = nonbloppy::findCgroup(controller);
        if (!parent) return;
        if (!makeCgroup(parent->directory() + "/nonbloppy_test_" + std::to_string(::getpid()), mDir)) return;
        for (const auto& [name, text] : parent->v1 ? v1Limits : v2Limits) {
            if (!writeFile(mDir + "/" + name, text)) {
                ::rmdir(mDir.c_str());
                mDir.clear();
                return;
            }
        }
        if (!child.empty() && !makeCgroup(mDir + "/" + child, mChild)) {
            ::rmdir(mDir.c_str());
            mDir.clear();
        }
    }
    ~ScratchCgroup()
    {
        // Empty again once the commands ended.
        if (!mChild.empty()) ::rmdir(mChild.c_str());
        if (!mDir.empty()) ::rmdir(mDir.c_str());
    }
    /// A shell prefix that moves the command after it into the cgroup (its child, if made);
    /// empty where none could be made.
    std::string enter() const
    {
        const std::string& where = mChild.empty() ? mDir : mChild;
        return where.empty() ? std::string() : "echo $$ > " + quote(where + "/cgroup.procs") + " && exec ";
    }

private:
    static bool makeCgroup(const std::string& dir, std::string& made)
    {
        if (::mkdir(dir.c_str(), 0755) != 0) return false;
        // A cgroup file system fills a new directory with its files; a plain one (a tmpfs
        // where the layout is another) does not, and the test would limit nothing.
        if (::access((dir + "/cgroup.procs").c_str(), F_OK) != 0) {
            std::error_code ec;
            std::filesystem::remove_all(dir, ec);
            return false;
        }
        made = dir;
        return true;
    }
    static bool writeFile(const std::string& path, const std::string& text)
    {
        std::ofstream file(path);
        file << text << std::flush;
        return bool(file);
    }
    std::string mDir, mChild;
};

TEST_F(CliTest, ThreadsDefaultToTheCpuLimitOfTheCgroup)
{
    // docker run --cpus 0.5, or a Kubernetes pod's limits.cpu: TBB would start a worker per
    // core all the same, which the kernel then throttles. mesh and convert run as many as
    // the limit rounds up to unless --threads says otherwise; the output does not change.
    if (tbb::info::default_concurrency() < 2) GTEST_SKIP() << "one core: no limit to lower";
    const ScratchCgroup halfCpu(nonbloppy::CgroupController::Cpu,
                                {{"cpu.cfs_period_us", "100000"}, {"cpu.cfs_quota_us", "50000"}},
                                {{"cpu.max", "50000 100000"}});
    const std::string enter = halfCpu.enter();
    if (enter.empty()) GTEST_SKIP() << "cannot make a cgroup with a CPU limit here";
    const RunResult limited = runAfter(enter, "mesh " + quote(kCube) + " -o " + quote(out("limited.obj")));
    ASSERT_EQ(limited.exitCode, 0) << limited.err;
    EXPECT_NE(limited.out.find("\n  threads              1              (the cgroup's CPU limit, 0.5 CPUs)\n"),
              std::string::npos) << limited.out;
    const RunResult given = runAfter(enter, "mesh " + quote(kCube) + " -o " + quote(out("given.obj")) + " --threads 2");
    ASSERT_EQ(given.exitCode, 0) << given.err;
    EXPECT_NE(given.out.find("\n  threads              2              (given)\n"), std::string::npos) << given.out;
    const RunResult free = run("mesh " + quote(kCube) + " -o " + quote(out("free.obj")));
    ASSERT_EQ(free.exitCode, 0) << free.err;
    EXPECT_NE(free.out.find("              (default)\n"), std::string::npos) << free.out;
    EXPECT_EQ(readText(out("limited.obj")), readText(out("free.obj")));
    EXPECT_EQ(readText(out("given.obj")), readText(out("free.obj")));
    const RunResult converted = runAfter(enter, "convert " + quote(kCube) + " " + quote(out("cube.ply")));
    EXPECT_EQ(converted.exitCode, 0) << converted.err;
}

TEST_F(CliTest, AParentCgroupsMemoryLimitBinds)
{
    // Slurm limits a job's memory and runs its steps in cgroups below it; Kubernetes limits a
    // pod above its containers; systemd a slice above its services. The memory checks read
    // only the process's own cgroup and the root, so under such a parent's limit the 6 GB
    // density grid was not refused: the kernel's OOM killer ended the run (exit 137).
    const ScratchCgroup job(nonbloppy::CgroupController::Memory, {{"memory.limit_in_bytes", "1500M"}},
                            {{"memory.max", "1500M"}}, "step");
    const std::string enter = job.enter();
    if (enter.empty()) GTEST_SKIP() << "cannot make a cgroup with a memory limit here";
    const std::string input = writeSparseParticles();
    const double headroom = expectSparseParticlesRefused(runAfter(enter, meshSparseParticles(input)), input);
    // The job's 1.57 GB (1500 MiB) less what the process and the page cache charged to it
    // hold by then.
    EXPECT_GT(headroom, 1.0);
    EXPECT_LE(headroom, 1.573);
}

TEST_F(CliTest, AParticleBoxMeshesOnlyTheParticlesInsideIt)
{
    // The dam-break frame cut at x = 0: the same mesh, attributes and all, as meshing a file
    // holding only the particles with x <= 0 (cut here by the library, written as PLY).
    const openvdb::BBoxd box(openvdb::Vec3d(-10.0, -10.0, -10.0), openvdb::Vec3d(0.0, 10.0, 10.0));
    const nonbloppy::ParticleSet half = nonbloppy::cropParticles(nonbloppy::readParticles(kDamBreak), box);
    nonbloppy::writeParticles(half, in("half.ply"));
    const RunResult cropped =
        run("mesh " + quote(kDamBreak) + " -o " + quote(out("cropped.ply")) + " --attributes id --particle-box -10 -10 -10 0 10 10");
    ASSERT_EQ(cropped.exitCode, 0) << cropped.err;
    const RunResult written = run("mesh " + quote(in("half.ply")) + " -o " + quote(out("half.ply")) + " --attributes id");
    ASSERT_EQ(written.exitCode, 0) << written.err;
    EXPECT_EQ(readText(out("cropped.ply")), readText(out("half.ply")));
    EXPECT_NE(cropped.out.find("\n  particles            " + std::to_string(half.size()) +
                               "          (of 24389, inside --particle-box (-10, -10, -10) -> (0, 10, 10))\n"),
              std::string::npos) << cropped.out;
    EXPECT_NE(cropped.out.find("\n  crop particles "), std::string::npos) << cropped.out;  // its timing
    // The surface closes around the kept particles, at most r_e past the box's face x = 0.
    const size_t radiusAt = cropped.out.find("\n  radius r_e ");
    ASSERT_NE(radiusAt, std::string::npos) << cropped.out;
    const double radius = std::stod(cropped.out.substr(radiusAt + 14));
    float farthest = -1e30f;
    for (const openvdb::Vec3s& p : nonbloppy::readMesh(out("cropped.ply")).points) farthest = std::max(farthest, p.x());
    EXPECT_GT(farthest, 0.0f);
    EXPECT_LT(farthest, radius);
    EXPECT_GT(half.size(), 10000u);
    EXPECT_LT(half.size(), 20000u);
}

TEST_F(CliTest, ABadParticleBoxIsRefused)
{
    const auto refused = [&](const std::string& box) { return run("mesh " + quote(kDamBreak) + " -o " + quote(out("m.ply")) + " --particle-box " + box); };
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"-1 -1 -1 1 -2 1", "nonbloppy: --particle-box: its minimum y -1 exceeds its maximum -2\n"},
        {"-1 -1 -1 1 nan 1", "nonbloppy: --particle-box: its maximum y is nan, not a finite number\n"},
        {"-1 -1 -1 1 1 1e400", "nonbloppy: --particle-box 1e400 lies outside double's range (it reads as infinity)\n"},
        {"-1 -1 0x1 1 1 1", "nonbloppy: --particle-box needs a number, got '0x1'\n"},
    };
    for (const auto& [box, message] : cases) {
        SCOPED_TRACE(box);
        const RunResult r = refused(box);
        EXPECT_EQ(r.exitCode, 2);
        EXPECT_EQ(r.err, message);
    }
    // A box that holds none of the particles: said once the file is read, exit 1.
    const RunResult empty = refused("10 10 10 11 11 11.5");
    EXPECT_EQ(empty.exitCode, 1);
    EXPECT_EQ(empty.err, "nonbloppy: none of the 24389 particles of " + kDamBreak +
                             " lie inside --particle-box (10, 10, 10) -> (11, 11, 11.5)\n");
    EXPECT_TRUE(listDir(dir() + "/out").empty());
}

TEST_F(CliTest, ConvertWithAParticleBoxWritesOnlyTheParticlesInsideIt)
{
    const nonbloppy::ParticleSet half = nonbloppy::cropParticles(
        nonbloppy::readParticles(kDamBreak), openvdb::BBoxd(openvdb::Vec3d(-10.0), openvdb::Vec3d(0.0, 10.0, 10.0)));
    const RunResult r = run("convert " + quote(kDamBreak) + " " + quote(out("half.ply")) + " --particle-box -10 -10 -10 0 10 10");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.out, "converted " + std::to_string(half.size()) +
                         " particles (of 24389, inside --particle-box (-10, -10, -10) -> (0, 10, 10)) with 2 attributes: " +
                         kDamBreak + " -> " + out("half.ply") + "\n");
    const nonbloppy::ParticleSet written = nonbloppy::readParticles(out("half.ply"));
    EXPECT_EQ(written.positions, half.positions);
    ASSERT_EQ(written.attributes.size(), 2u);
    EXPECT_EQ(written.attributes[0].bytes, half.attributes[0].bytes);  // id
    EXPECT_EQ(written.attributes[1].bytes, half.attributes[1].bytes);  // velocity
    // None inside: the (empty) file is written, as any file of no particles is, and said.
    const RunResult none = run("convert -q " + quote(kDamBreak) + " " + quote(out("none.csv")) + " --particle-box 10 10 10 11 11 11");
    EXPECT_EQ(none.exitCode, 0);
    EXPECT_EQ(none.err, "nonbloppy: warning: none of the 24389 particles of " + kDamBreak +
                            " lie inside --particle-box (10, 10, 10) -> (11, 11, 11): " + out("none.csv") +
                            " holds no particles\n");
    EXPECT_EQ(nonbloppy::readParticles(out("none.csv")).size(), 0u);
    // A bad box: exit 2, nothing read or written.
    const RunResult bad = run("convert " + quote(kDamBreak) + " " + quote(out("bad.csv")) + " --particle-box 0 0 0 1 1 -1");
    EXPECT_EQ(bad.exitCode, 2);
    EXPECT_EQ(bad.err, "nonbloppy: --particle-box: its minimum z 0 exceeds its maximum -1\n");
    EXPECT_EQ(listDir(dir() + "/out"), (std::vector<std::string>{"half.ply", "none.csv"}));
}

TEST_F(CliTest, OutputDoesNotDependOnThreadCount)
{
    const RunResult one = meshCube("t1", "--threads 1");
    ASSERT_EQ(one.exitCode, 0) << one.err;
    // The summary says the run had the one thread it was given.
    EXPECT_NE(one.out.find("\n  threads              1              (given)\n"), std::string::npos) << one.out;
    ASSERT_EQ(meshCube("t2", "-q --threads 2").exitCode, 0);
    EXPECT_TRUE(readText(out("t1.obj")) == readText(out("t2.obj"))) << "OBJ files differ";
    EXPECT_TRUE(readText(out("t1.vdb")) == readText(out("t2.vdb"))) << ".vdb files differ";

    // Smoothing sums over neighbouring vertices and attributes over neighbouring particles:
    // the paths where the order of a parallel sum would show. The dam break carries id and
    // velocity; the cube carries nothing.
    const std::string dam = kDamBreak;
    for (const char* threads : {"1", "2"}) {
        const std::string name = std::string("dam") + threads;
        const RunResult r = run("mesh " + quote(dam) + " -o " + quote(out(name + ".ply")) + " --vdb "
                                + quote(out(name + ".vdb")) + " --spacing 0.05 --attributes all --threads " + threads);
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_NE(r.out.find("\n  smoothing            on             (with the volume offset)\n"), std::string::npos)
            << r.out;
    }
    const std::string ply = readText(out("dam1.ply"));
    EXPECT_NE(ply.find("\nproperty int id\nproperty float velocity_x\n"), std::string::npos) << ply.substr(0, 400);
    EXPECT_TRUE(ply == readText(out("dam2.ply"))) << "PLY files differ";
    EXPECT_TRUE(readText(out("dam1.vdb")) == readText(out("dam2.vdb"))) << ".vdb files differ";
}

TEST_F(CliTest, NoDirectIoWritesTheSameMesh)
{
    // The dam-break frame's PLY (2.7 MB) is over the 1 MiB from which meshes bypass the page
    // cache; --no-direct-io writes it through the cache, with the same bytes.
    if (!nonbloppy::directIoSuitable(dir())) GTEST_SKIP() << "no direct I/O on " << dir();
    const std::string frame = quote(kDamBreak);
    ASSERT_EQ(run("mesh " + frame + " -o " + quote(out("direct.ply")) + " -q").exitCode, 0);
    ASSERT_EQ(run("mesh " + frame + " -o " + quote(out("cached.ply")) + " -q --no-direct-io").exitCode, 0);
    const std::string direct = readText(out("direct.ply"));
    EXPECT_GT(direct.size(), size_t(1) << 20);
    EXPECT_TRUE(direct == readText(out("cached.ply"))) << "PLY files differ";
}

TEST_F(CliTest, MissingInputFile)
{
    const std::string missing = in("missing.vtk");
    expectFailure("mesh " + quote(missing) + " -o " + quote(out("x.obj")),
                  "cannot open " + missing + ": No such file or directory");
}

TEST_F(CliTest, UnknownInputExtension)
{
    const std::string path = in("particles.foo");
    writeText(path, "1 2 3\n");
    // A format nonbloppy cannot read is a command line that cannot run (exit 2), as an unknown
    // output format is; it used to exit 1, telling scripts the file was at fault.
    const std::string expected = "; expected .vtk, .vtu, .vtp, .ply, .xyz, .bgeo, .vdb, .csv, .txt or .json";
    const std::string message = "unknown particle file extension '.foo' (" + path + ")" + expected;
    expectFailure("mesh " + quote(path) + " -o " + quote(out("x.obj")), message, 2);
    expectFailure("convert " + quote(path) + " " + quote(out("x.ply")), message, 2);
    // Told from the name alone: also for a file that is missing, and for a sequence with no
    // frame on disk.
    expectFailure("inspect " + quote(in("missing.md")),
                  "unknown file extension '.md' (" + in("missing.md")
                      + "); expected .vdb, .obj, .ply, .vtk, .vtu, .vtp, .xyz, .bgeo, .csv, .txt or .json", 2);
    const std::string pattern = in("fluid_{}.foo");
    expectFailure("mesh " + quote(pattern) + " -o " + quote(out("m_{}.obj")),
                  "unknown particle file extension '.foo' (" + pattern + ")" + expected, 2);
    const std::string houdini = in("particles.bgeo.sc");
    writeText(houdini, "1 2 3\n");
    const RunResult r = run("inspect " + quote(houdini));
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_EQ(r.err.rfind("nonbloppy: unknown particle file extension '.sc' (" + houdini + "): Houdini's", 0), 0u) << r.err;
}

TEST_F(CliTest, TruncatedInput)
{
    const std::string path = in("truncated.vtk");
    writeText(path, readText(kCube).substr(0, 300));
    expectFailure("mesh " + quote(path) + " -o " + quote(out("x.obj")),
                  "truncated POINTS section (" + path + ")");
    // -v: the stage that threw is not said to be done.
    const RunResult verbose = run("mesh " + quote(path) + " -o " + quote(out("x.obj")) + " -v");
    EXPECT_EQ(verbose.exitCode, 1);
    const std::vector<std::string> errLines = lines(verbose.err);
    ASSERT_EQ(errLines.size(), 3u) << verbose.err;
    EXPECT_EQ(errLines[0], "[progress] read particles ...");
    EXPECT_EQ(errLines[1].rfind("[progress] read particles failed (", 0), 0u) << errLines[1];
    EXPECT_EQ(errLines[2], "nonbloppy: truncated POINTS section (" + path + ")");
}

TEST_F(CliTest, NanCoordinate)
{
    // The reader takes the token 'nan' as a value; the position check names the particle.
    const std::string path = in("nan.vtk");
    writeText(path, "# vtk DataFile Version 3.0\nnan test\nASCII\nDATASET POLYDATA\n"
                    "POINTS 3 float\n0 0 0\n1 nan 0\n0 1 0\n");
    expectFailure("mesh " + quote(path) + " -o " + quote(out("x.obj")),
                  "non-finite position of particle 1 (" + path + ")");
}

TEST_F(CliTest, ZeroParticles)
{
    const std::string path = in("empty.vtk");
    writeText(path, "# vtk DataFile Version 3.0\nempty\nASCII\nDATASET POLYDATA\nPOINTS 0 float\n");
    expectFailure("mesh " + quote(path) + " -o " + quote(out("x.obj")), "no particles in " + path);
}

TEST_F(CliTest, ParticlesStackedOnEachOtherAskForTheSpacing)
{
    // Every particle written three times (an exporter that repeats its substeps): the median
    // nearest-neighbour distance is 0, so there is no spacing to estimate; the run says so
    // rather than meshing at a made-up one.
    std::string csv = "x,y,z\n";
    for (int i = 0; i < 5 * 5 * 5; ++i) {
        const std::string row = std::to_string(0.1 * (i % 5)) + "," + std::to_string(0.1 * (i / 5 % 5)) + ","
                                + std::to_string(0.1 * (i / 25)) + "\n";
        csv += row + row + row;
    }
    const std::string path = in("stacked.csv");
    writeText(path, csv);
    expectFailure("mesh " + quote(path) + " -o " + quote(out("x.obj")),
                  path + ": cannot estimate the particle spacing: most particles sit on top of another one; give "
                  "--spacing");
}

TEST_F(CliTest, BadParameters)
{
    const std::string base = "mesh " + quote(kCube) + " -o " + quote(out("x.obj")) + " --vdb "
                             + quote(out("x.vdb")) + " ";
    // Each value is out of range whatever the particles: a bad command line, exit 2.
    expectUsageError(base + "--radius 0", "--radius must be > 0, got 0");
    expectUsageError(base + "--radius=-1", "--radius must be > 0, got -1");
    expectUsageError(base + "--voxel-size 0", "--voxel-size must be > 0, got 0");
    expectUsageError(base + "--voxel-size inf", "--voxel-size must be finite, got inf");
    expectUsageError(base + "--radius nan", "--radius must be finite, got nan");
    expectUsageError(base + "--blend 1.5", "--blend must lie in [0,1], got 1.5");
    expectUsageError(base + "--blend=-0.1", "--blend must lie in [0,1], got -0.1");
    expectUsageError(base + "-c 2", "--blend must lie in [0,1], got 2");
    expectUsageError(base + "--iterations=-1", "--iterations must be >= 0, got -1");
    expectUsageError(base + "--adaptivity 1.5", "--adaptivity must lie in [0,1], got 1.5");
    expectUsageError(base + "--region-leaves -1", "--region-leaves must be >= 0, got -1");
    // Options of the faithful method alone would be ignored by the paper's.
    expectUsageError(base + "--method paper --max-step 0.01", "--max-step applies to --method faithful only, not paper");
    expectUsageError(base + "--method paper --no-smooth", "--no-smooth applies to --method faithful only, not paper");
    expectUsageError(base + "--threads 0", "--threads must lie in [1, 4096], got 0");
    expectUsageError(base + "--threads 100000000", "--threads must lie in [1, 4096], got 100000000");
    // An empty value was read as 0.
    expectUsageError(base + "--blend ''", "--blend needs a number, got ''");
    expectUsageError(base + "--adaptivity ''", "--adaptivity needs a number, got ''");
    expectUsageError(base + "--max-step ''", "--max-step needs a number, got ''");  // was "no cap"
    // Given lengths judged against each other or OpenVDB's limits: also before the input is
    // read (these exited 1 after reading it).
    expectUsageError(base + "--voxel-size 0.001 --radius 1",
                     "--voxel-size 0.001 is too small for --radius 1: at most 32 voxels per radius");
    expectUsageError(base + "--voxel-size 0.2 --radius 0.1",
                     "--voxel-size 0.2 is too large for --radius 0.1: at least one voxel per radius");
    expectUsageError(base + "--voxel-size 1e-6",
                     "--voxel-size 1e-06 is below 1.5e-05, the smallest OpenVDB accepts: give the positions in a "
                     "smaller unit");
    expectUsageError(base + "--radius 2e18 --voxel-size 1e18",
                     "--radius 2e+18 is too large: at most 1e+18 (lengths are squared in single precision); give the "
                     "positions in a larger unit");
    // Lengths a given spacing sets (r_e = 2 s, h = s/2): before the input too, named so.
    expectUsageError(base + "--spacing 0.05 --radius 50",
                     "--spacing 0.05: the voxel size 0.5 s = 0.025 is too small for --radius 50: at most 32 voxels "
                     "per radius");
    expectUsageError(base + "--spacing 1e-6",
                     "--spacing 1e-06: the voxel size 0.5 s = 5e-07 is below 1.5e-05, the smallest OpenVDB accepts: "
                     "give the positions in a smaller unit");
    expectUsageError(base + "--spacing 1e308",
                     "--spacing 1e+308: the radius 2 s = inf is too large: at most 1e+18 (lengths are squared in "
                     "single precision); give the positions in a larger unit");
    // Past double's range the text read as 0 or inf: "--spacing must be > 0, got 0".
    expectUsageError(base + "--spacing 1e-400", "--spacing 1e-400 lies outside double's range (it reads as 0)");
    expectUsageError(base + "--radius 1e400", "--radius 1e400 lies outside double's range (it reads as infinity)");
    // A threshold a float density cannot hold: 1e-46 became 0, an empty mesh blamed on the
    // particles.
    expectUsageError(base + "--threshold 1e-46",
                     "--threshold must be a positive number within float's range (the density grid's values), got "
                     "1e-46");
    expectUsageError(base + "--threshold 1e39",
                     "--threshold must be a positive number within float's range (the density grid's values), got "
                     "1e+39");
    // A given spacing and radius too far apart for the threshold's calibration (over a
    // kernel 1000 spacings wide it would take hours): before the input too.
    expectUsageError(base + "--spacing 0.05 --radius 50 --voxel-size 2",
                     "--radius must be at most 32 particle spacings to calibrate --threshold, got 1000 spacings; "
                     "give --threshold");
    // Lengths derived from the estimated spacing (0.0498): refused once it is known, exit 1,
    // the input and the estimate named. (Unchecked, --radius 0.001 estimated the spacing
    // through an index of cells r_e/2 = 0.0005, which took 40 s.)
    expectFailure(base + "--radius 0.001",
                  kCube + ": --spacing 0.0498381 (estimated): the voxel size 0.5 s = 0.0249191 is too large for "
                  "--radius 0.001: at least one voxel per radius");
    expectFailure(base + "--voxel-size 64",
                  kCube + ": --spacing 0.0498381 (estimated): --voxel-size 64 is too large for the radius 2 s = "
                  "0.0996763: at least one voxel per radius");
    expectFailure(base + "--radius 50 --voxel-size 2",
                  kCube + ": --radius must be at most 32 particle spacings to calibrate --threshold, got 1003.25 "
                  "spacings; give --threshold");
}

TEST_F(CliTest, NegativeValuesWithSpace)
{
    // "--radius -1" (with a space) must read -1 as the value, not as an option.
    expectUsageError("mesh " + quote(kCube) + " -o " + quote(out("x.obj")) + " --radius -1",
                  "--radius must be > 0, got -1");
    expectUsageError("mesh " + quote(kCube) + " -o " + quote(out("x.obj")) + " --blend -0.1",
                  "--blend must lie in [0,1], got -0.1");
}

TEST_F(CliTest, OutputInMissingDirectory)
{
    const std::string target = dir() + "/no/such/dir/x.obj";
    expectFailure("mesh " + quote(kCube) + " -o " + quote(target),
                  "cannot write " + target + ": No such file or directory");
    // The same for the .vdb cache, before the mesh is written.
    const std::string vdb = dir() + "/no/such/dir/x.vdb";
    expectFailure("mesh " + quote(kCube) + " -o " + quote(out("x.obj")) + " --vdb " + quote(vdb),
                  "cannot write " + vdb + ": No such file or directory");
}

TEST_F(CliTest, UnknownOutputExtension)
{
    const std::string target = out("x.stl");
    expectUsageError("mesh " + quote(kCube) + " -o " + quote(target),
                  "unknown mesh file extension '.stl' (" + target + "); expected .obj, .ply or .vtk");
}

TEST_F(CliTest, BadVdbNameAndInputAsOutput)
{
    const std::string vdb = out("x.cache");
    expectUsageError("mesh " + quote(kCube) + " -o " + quote(out("x.obj")) + " --vdb " + quote(vdb),
                  "--vdb file name must end in .vdb (" + vdb + ")");
    const std::string copy = in("cube.vtk");
    fs::copy_file(kCube, copy);
    const RunResult r = run("mesh " + quote(copy) + " -o " + quote(copy));
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_EQ(r.err, "nonbloppy: cannot write " + copy + ": it is the input file\n");
    EXPECT_EQ(readText(copy), readText(kCube));
}

TEST_F(CliTest, InspectUnknownExtension)
{
    const std::string path = in("notes.md");
    writeText(path, "hello\n");
    const RunResult r = run("inspect " + quote(path));
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_EQ(r.err, "nonbloppy: unknown file extension '.md' (" + path
                         + "); expected .vdb, .obj, .ply, .vtk, .vtu, .vtp, .xyz, .bgeo, .csv, .txt "
                           "or .json\n");
}

TEST_F(CliTest, InspectRefusesAFifoInsteadOfWaitingForIt)
{
    // inspect opens its file more than once: a FIFO's writer left after the first read and
    // the second open() waited for another one for ever. No writer is needed to refuse it.
    const std::string fifo = in("fifo.vtk");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    const RunResult r = run("inspect " + quote(fifo));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "nonbloppy: cannot inspect " + fifo + ": not a regular file (inspect reads it more than once; "
                     "save it to a file first)\n");
}

TEST_F(CliTest, InspectBrokenMeshIsNotCalledAParticleFile)
{
    // Its vertices alone would read as three particles.
    const std::string path = in("broken.ply");
    writeText(path, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                    "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
    const RunResult r = run("inspect " + quote(path));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "nonbloppy: polygon 0 references vertex 7 but the file has 3 vertices (" + path + ")\n");
    EXPECT_EQ(r.out, "");
}

TEST_F(CliTest, InspectTruncatedMeshIsNotCalledAParticleFile)
{
    // Cut inside its face list: the vertices are whole and would read as particles.
    const std::string mesh = out("cube.ply");
    ASSERT_EQ(run("mesh " + quote(kCube) + " -q -o " + quote(mesh)).exitCode, 0);
    const std::string bytes = readText(mesh);
    const std::string path = in("cut.ply");
    writeText(path, bytes.substr(0, bytes.size() - 100));
    const RunResult r = run("inspect " + quote(path));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "nonbloppy: truncated PLY face element (" + path + ")\n");
    EXPECT_EQ(r.out, "");
}

TEST_F(CliTest, InspectTruncatedVdbIsOneLine)
{
    // Cut inside a grid: io::File took a minute and 8.5 GB on such a file and printed a
    // 1.4 GB line; cut in its header, it reported "0 grids", exit 0. The cube's cache holds
    // one grid, density, which ends where the file does.
    ASSERT_EQ(meshCube("cube", "-q").exitCode, 0);
    const std::string bytes = readText(out("cube.vdb"));
    const size_t half = bytes.size() / 2;
    const std::vector<std::pair<size_t, std::string>> cuts = {
        {4, "not a VDB file"},
        {64, "truncated or corrupt metadata of the file: it claims 1 item, at least 12 bytes each, and 3 bytes are "
             "left"},
        {half, "truncated grid 'density' (it ends at byte " + std::to_string(bytes.size()) + ", the file has "
                   + std::to_string(half) + ")"},
    };
    for (const auto& [size, reason] : cuts) {
        SCOPED_TRACE(size);
        const std::string path = in("cut.vdb");
        writeText(path, bytes.substr(0, size));
        const RunResult r = run("inspect " + quote(path));
        EXPECT_EQ(r.exitCode, 1);
        EXPECT_EQ(r.err, "nonbloppy: cannot read .vdb file: " + reason + " (" + path + ")\n");
        EXPECT_EQ(r.out, "");
    }
}

TEST_F(CliTest, EmptyMeshIsWrittenWithAWarning)
{
    // A frame of spray may mesh to nothing; an out-of-scale --threshold did so without a word.
    const RunResult r = run("mesh " + quote(kCube) + " -q -o " + quote(out("empty.obj")) + " --threshold 1e30");
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_EQ(r.err, "nonbloppy: warning: " + out("empty.obj")
                         + " is empty: the density of the 2366 particles, sampled at --voxel-size 0.0249191, "
                           "nowhere reaches --threshold 1e+30\n");
    EXPECT_TRUE(fs::exists(out("empty.obj")));
    // PLY and VTK declare the normals a non-empty mesh has, and inspect calls them meshes.
    for (const std::string name : {"empty.ply", "empty.vtk"}) {
        ASSERT_EQ(run("mesh " + quote(kCube) + " -q -o " + quote(out(name)) + " --threshold 1e30").exitCode, 0);
        const std::string bytes = readText(out(name));
        EXPECT_NE(bytes.find(name == "empty.ply" ? "property float nx\n" : "NORMALS normals float\n"), std::string::npos)
            << bytes;
        const RunResult inspect = run("inspect " + quote(out(name)));
        EXPECT_EQ(inspect.exitCode, 0) << inspect.err;
        EXPECT_EQ(inspect.out.rfind(out(name) + ": mesh\n  vertices         0\n", 0), 0u) << inspect.out;
        EXPECT_NE(inspect.out.find("\n  attributes       none\n"), std::string::npos) << inspect.out;
    }
    const RunResult normal = run("mesh " + quote(kCube) + " -q -o " + quote(out("cube.obj")));
    EXPECT_EQ(normal.err, "");
}

TEST_F(CliTest, VerticesWithoutANormalAreSaid)
{
    // -c 1 moves every vertex onto its particles' mean: the isolated droplets of this frame
    // collapse to points, whose vertices got (0,0,0) normals without a word (bug hunt).
    const std::string free = kData + "/free_particles_125_particles.vtk";
    const RunResult r = run("mesh " + quote(free) + " -q -o " + quote(out("c1.obj")) + " -c 1 --method paper");
    EXPECT_EQ(r.exitCode, 0);
    const std::string mesh = readText(out("c1.obj"));
    size_t zero = 0;
    for (size_t at = mesh.find("\nvn 0 0 0\n"); at != std::string::npos; at = mesh.find("\nvn 0 0 0\n", at + 1)) ++zero;
    ASSERT_GT(zero, 0u);
    EXPECT_EQ(r.err, "nonbloppy: warning: " + std::to_string(zero) + " of the 1032 vertices of " + out("c1.obj") +
                         " have no normal (the faces around them have no area): -c 1 collapses droplets onto their "
                         "particles; lower --blend\n");
    EXPECT_EQ(run("mesh " + quote(free) + " -q -o " + quote(out("c3.obj")) + " -c 0.3 --method paper").err, "");
}

TEST_F(CliTest, UsageErrorsAreOneLine)
{
    // Missing pieces of the command line are said in the tool's words, not CLI11's.
    expectUsageError("", "no command given; commands are mesh, inspect, convert, help");
    expectUsageError("mesh", "IN is required");
    expectUsageError("mesh " + quote(kCube), "--output is required");
    expectUsageError("frobnicate", "unknown command 'frobnicate'; commands are mesh, inspect, convert, help");
    expectUsageError("mesh " + quote(kCube) + " -o x.obj --radius abc", "--radius needs a number, got 'abc'");
}

TEST_F(CliTest, UnreadableNumbersAreNamed)
{
    // CLI11 says "Could not convert: --threads = abc"; the tool says it as its own checks do.
    const std::string base = "mesh " + quote(kCube) + " -o " + quote(out("x.obj")) + " ";
    expectUsageError(base + "--threads abc", "--threads needs an integer, got 'abc'");
    expectUsageError(base + "--iterations 2.5", "--iterations needs an integer, got '2.5'");
    expectUsageError(base + "--iterations 99999999999", "--iterations 99999999999 is out of range");
    expectUsageError(base + "--threads -99999999999", "--threads -99999999999 is out of range");
    // Past 2^63 it was clamped to 9223372036854775807 without a word.
    expectUsageError(base + "--region-leaves 99999999999999999999", "--region-leaves 99999999999999999999 is out of range");
    expectUsageError(base + "--blend x", "--blend needs a number, got 'x'");
    expectUsageError(base + "--radius 0.1m", "--radius needs a number, got '0.1m'");
    expectUsageError(base + "--frame-jobs 1e3", "--frame-jobs needs an integer, got '1e3'");
}

TEST_F(CliTest, NumbersAreReadAsDecimalOnly)
{
    // CLI11 reads integers with strtoll in base 0 and reals with strtold: "-t 010" ran 8
    // iterations (octal), "-t 08" was "out of range", hexadecimal and leading blanks were
    // taken (hostile-input audit).
    const std::string base = "mesh " + quote(kCube) + " -o " + quote(out("x.obj")) + " ";
    expectUsageError(base + "--iterations 0x10", "--iterations needs an integer, got '0x10'");
    expectUsageError(base + "--spacing 0x1p-4", "--spacing needs a number, got '0x1p-4'");
    expectUsageError(base + "--threads ' 1'", "--threads needs an integer, got ' 1'");
    expectUsageError(base + "--radius '0.1 '", "--radius needs a number, got '0.1 '");
    expectUsageError(base + "--voxel-size 1e", "--voxel-size needs a number, got '1e'");
    const RunResult r = run(base + "-t 010 --threads 02 --spacing .05");
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("  iterations t         10 "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("  threads              2 "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("  spacing s            0.05 "), std::string::npos) << r.out;
}

TEST_F(CliTest, CommandLineMistakesAreSaidInTheToolsWords)
{
    // CLI11's own wording ("A subcommand is required", "--blend: 1 required FLOAT missing",
    // "At Most 1 required but received 2", "The following argument was not expected") named
    // neither the unknown command nor what was wrong with an option.
    const std::string commands = "commands are mesh, inspect, convert, help";
    expectUsageError("", "no command given; " + commands);
    expectUsageError("frobnicate x", "unknown command 'frobnicate'; " + commands);
    expectUsageError("--bogus", "unknown option '--bogus'; " + commands);
    const std::string base = "mesh " + quote(kCube) + " -o " + quote(out("x.obj")) + " ";
    expectUsageError(base + "--bogus 3", "mesh has no option '--bogus'; see 'nonbloppy help mesh'");
    // CLI11 checks required arguments first: these said "IN is required" (hostile-input audit).
    expectUsageError("mesh --bogus", "mesh has no option '--bogus'; see 'nonbloppy help mesh'");
    expectUsageError("mesh --version", "mesh has no option '--version'; see 'nonbloppy help mesh'");
    expectUsageError("convert --frobnicate", "convert has no option '--frobnicate'; see 'nonbloppy help convert'");
    expectUsageError(base + "extra.vtk more.vtk", "unexpected argument 'extra.vtk' to mesh; see 'nonbloppy help mesh'");
    expectUsageError(base + "--blend", "--blend needs a number");
    expectUsageError(base + "--threads", "--threads needs an integer");
    expectUsageError("mesh " + quote(kCube) + " -o", "--output needs a value");
    expectUsageError(base + "-c 0.3 -c 0.4", "--blend given 2 times; give it once");
    expectUsageError("inspect " + quote(kCube) + " other.vtk",
                     "unexpected argument 'other.vtk' to inspect; see 'nonbloppy help inspect'");
}

TEST_F(CliTest, AFailedVdbWriteLeavesTheEarlierMeshInPlace)
{
    // The mesh is written before the .vdb; when the .vdb then failed, removing the new mesh
    // also lost the one an earlier run had left there.
    const std::string mesh = out("keep.obj");
    ASSERT_EQ(run("mesh " + quote(kCube) + " -q -o " + quote(mesh)).exitCode, 0);
    const std::string before = readText(mesh);
    ASSERT_FALSE(before.empty());
    const RunResult r = run("mesh " + quote(kCube) + " -q -c 0.1 -o " + quote(mesh) + " --vdb /proc/nonbloppy.vdb");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "nonbloppy: cannot write /proc/nonbloppy.vdb: No such file or directory\n");
    EXPECT_EQ(readText(mesh), before);
    EXPECT_EQ(listDir(out("")), std::vector<std::string>{"keep.obj"});  // no link to the old file left
    // An output name too long for the link's usual name beside it (bug hunt: the link
    // failed, and the old mesh was lost).
    const std::string longName = std::string(250, 'm') + ".obj";
    fs::rename(mesh, out(longName));
    const RunResult again = run("mesh " + quote(kCube) + " -q -c 0.1 -o " + quote(out(longName)) +
                                " --vdb /proc/nonbloppy.vdb");
    EXPECT_EQ(again.exitCode, 1);
    EXPECT_EQ(readText(out(longName)), before);
    EXPECT_EQ(listDir(out("")), std::vector<std::string>{longName});
    fs::rename(out(longName), mesh);
    // A first run that fails the same way leaves nothing.
    fs::remove(mesh);
    EXPECT_EQ(run("mesh " + quote(kCube) + " -q -o " + quote(mesh) + " --vdb /proc/nonbloppy.vdb").exitCode, 1);
    EXPECT_TRUE(listDir(out("")).empty());
    // Through a link to a file yet to be written, which the writers follow: the undo removed
    // the link and left the new file.
    fs::create_symlink("target.obj", out("link.obj"));
    EXPECT_EQ(run("mesh " + quote(kCube) + " -q -o " + quote(out("link.obj")) + " --vdb /proc/nonbloppy.vdb").exitCode, 1);
    EXPECT_EQ(listDir(out("")), std::vector<std::string>{"link.obj"});
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(out("link.obj"))));
}

TEST_F(CliTest, AnOutputLinkedIntoAMissingDirectoryIsRefusedBeforeTheWork)
{
    // The check looked at the link's own directory; the writers follow the link, and the run
    // failed only after meshing (bug hunt).
    fs::create_symlink(out("nodir/x.vdb"), out("v.vdb"));
    const RunResult r = run("mesh " + quote(kCube) + " -v -o " + quote(out("m.obj")) + " --vdb " + quote(out("v.vdb")));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "nonbloppy: cannot write " + out("v.vdb") + ": No such file or directory\n");
    EXPECT_EQ(listDir(out("")), std::vector<std::string>{"v.vdb"});
}

TEST_F(CliTest, ASuccessfulRunOverEarlierOutputsLeavesOnlyTheNewOnes)
{
    // The replaced files lose their last link on a thread of their own (BackgroundRemover):
    // by the time the process exits they must be gone, and the new files in their place.
    auto meshTo = [&](const std::string& name, const char* blend) {
        return run("mesh " + quote(kDamBreak) + " -q -c " + blend +
                   " -o " + quote(out(name + ".ply")) + " --vdb " + quote(out(name + ".vdb")));
    };
    ASSERT_EQ(meshTo("dam", "0.1").exitCode, 0);
    const std::string before = readText(out("dam.ply"));
    ASSERT_EQ(meshTo("dam", "0.5").exitCode, 0);
    EXPECT_EQ(listDir(out("")), (std::vector<std::string>{"dam.ply", "dam.vdb"}));
    const std::string after = readText(out("dam.ply"));
    EXPECT_NE(after, before);
    ASSERT_EQ(meshTo("fresh", "0.5").exitCode, 0);
    EXPECT_EQ(after, readText(out("fresh.ply")));
}

TEST_F(CliTest, InspectMissingFile)
{
    const std::string missing = in("missing.vdb");
    const RunResult r = run("inspect " + quote(missing));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "nonbloppy: cannot open " + missing + ": No such file or directory\n");
}

TEST_F(CliTest, AnEmptyInputNameIsAUsageError)
{
    // An unset shell variable: "cannot open : No such file or directory" named nothing.
    for (const auto& [command, expected] :
         {std::pair<std::string, std::string>{"mesh '' -o " + quote(out("m.obj")), "IN needs a file name, got ''"},
          {"inspect ''", "FILE needs a file name, got ''"},
          {"convert '' " + quote(out("p.ply")), "IN needs a file name, got ''"},
          // Outputs too: "particle file name has no extension ()" (hostile-input audit).
          {"mesh " + quote(kCube) + " -o ''", "--output needs a file name, got ''"},
          {"convert " + quote(kCube) + " ''", "OUT needs a file name, got ''"}}) {
        const RunResult r = run(command);
        EXPECT_EQ(r.exitCode, 2) << command;
        EXPECT_EQ(r.err, "nonbloppy: " + expected + "\n") << command;
    }
    EXPECT_TRUE(listDir(dir() + "/out").empty());
}

TEST_F(CliTest, OnATerminalASingleFrameShowsItsStagesOnOneLine)
{
    // Long work shows progress: a single frame on a terminal was silent until its summary.
    // util-linux's script(1) gives the run a terminal.
    if (std::system("command -v script >/dev/null 2>&1") != 0) GTEST_SKIP() << "script(1) not installed";
    const std::string transcript = dir() + "/terminal.txt";
    const std::string command = "script -qec " + quote(quote(kCli) + " mesh " + quote(kCube) + " -o " + quote(out("cube.obj"))) +
                                " /dev/null >" + quote(transcript) + " 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << readText(transcript);
    const std::string shown = readText(transcript);
    for (const char* stage : {"\rread particles\033[K", "\rrasterize density", "\rextract surface", "\rwrite mesh"}) {
        EXPECT_NE(shown.find(stage), std::string::npos) << stage;
    }
    // Erased before the summary, which starts on a clean line.
    const size_t summary = shown.find("input");
    ASSERT_NE(summary, std::string::npos) << shown;
    EXPECT_EQ(shown.rfind("\r\033[K", summary), summary - 4) << shown;
    // Not through a pipe or file, nor with -q on the terminal: their output is unchanged.
    const RunResult piped = run("mesh " + quote(kCube) + " -o " + quote(out("cube2.obj")));
    ASSERT_EQ(piped.exitCode, 0) << piped.err;
    ASSERT_EQ(piped.out.compare(0, 6, "input\n"), 0) << piped.out;
    EXPECT_EQ(piped.out.find('\r'), std::string::npos);
    EXPECT_EQ(piped.err, "");
    const std::string quiet = "script -qec " +
                              quote(quote(kCli) + " mesh " + quote(kCube) + " -q -o " + quote(out("cube3.obj"))) +
                              " /dev/null >" + quote(transcript) + " 2>&1";
    ASSERT_EQ(std::system(quiet.c_str()), 0) << readText(transcript);
    EXPECT_EQ(readText(transcript), "");
    EXPECT_TRUE(fs::exists(out("cube3.obj")));
}

TEST_F(CliTest, SigintSigtermAndSighupCancelWithoutLeavingFiles)
{
    // A run long enough to be caught mid-way: a fine grid on the dam-break frame. The
    // progress line shows that the signal handlers are installed; interrupt then. SIGHUP
    // (terminal or ssh session closed) used to end the run at once, exit 129.
    for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
        SCOPED_TRACE(signal);
        const RunResult r = interruptWhen(
            {"mesh", kDamBreak, "-o", out("dam.obj"), "--vdb",
             out("dam.vdb"), "--voxel-size", "0.005", "-v"},
            [](const std::string& err) { return err.find("[progress] rasterize density") != std::string::npos; },
            signal);
        ASSERT_EQ(r.killedBy, 0) << "killed by the signal instead of handling it";
        EXPECT_EQ(r.exitCode, 130);
        const std::vector<std::string> errLines = lines(r.err);
        ASSERT_FALSE(errLines.empty());
        EXPECT_EQ(errLines.back(), "nonbloppy: interrupted");
        EXPECT_TRUE(listDir(dir() + "/out").empty()) << "output files left behind";
    }
}

TEST_F(CliTest, RepeatedSignalsWithinASecondAreOneRequest)
{
    // timeout(1) signals its child and then its whole process group: two SIGINTs at once. The
    // second used to end the process mid clean-up, leaving the new mesh beside the previous
    // run's .vdb and a backup of the old mesh.
    writeText(out("dam.obj"), "old mesh\n");
    writeText(out("dam.vdb"), "old grid\n");
    const RunResult r = interruptWhen(
        {"mesh", kDamBreak, "-o", out("dam.obj"), "--vdb",
         out("dam.vdb"), "--voxel-size", "0.005", "-v"},
        [](const std::string& err) { return err.find("[progress] rasterize density") != std::string::npos; },
        SIGINT, 2);
    ASSERT_EQ(r.killedBy, 0) << "killed by the second signal instead of handling the first";
    EXPECT_EQ(r.exitCode, 130);
    EXPECT_EQ(lines(r.err).back(), "nonbloppy: interrupted");
    EXPECT_EQ(listDir(dir() + "/out"), (std::vector<std::string>{"dam.obj", "dam.vdb"}));
    EXPECT_EQ(readText(out("dam.obj")), "old mesh\n");
    EXPECT_EQ(readText(out("dam.vdb")), "old grid\n");
}

TEST_F(CliTest, ASignalASecondAfterTheFirstEndsAStuckRun)
{
    // Reading a FIFO that nobody writes blocks in open(), where the first signal cannot stop
    // it; a second one, a second or more later, ends the process (the signal's default action).
    const std::string fifo = in("fifo.vtk");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    const RunResult r = interruptWhen(
        {"mesh", fifo, "-o", out("x.obj"), "-v"},
        [](const std::string& err) { return err.find("[progress] read particles") != std::string::npos; },
        SIGTERM, 2, std::chrono::milliseconds(1300));
    EXPECT_EQ(r.killedBy, SIGTERM);
    EXPECT_TRUE(listDir(dir() + "/out").empty());
}

TEST_F(CliTest, AReadStuckOnTheFirstSignalEndsAfterAGrace)
{
    // `timeout 20 nonbloppy mesh fifo.vtk` never ended (hostile-input audit): timeout's two
    // SIGTERMs arrive together and count as one request, which a run blocked opening a FIFO
    // that nobody writes cannot act on. kStuckReadSeconds (2 s) later, still reading and with
    // no output pending, it takes the signal's default action; mesh and convert alike.
    for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
             {"mesh", in("fifo.vtk"), "-o", out("x.obj"), "-v"}, {"convert", in("fifo.vtk"), out("x.ply")}}) {
        SCOPED_TRACE(args[0]);
        const std::string fifo = in("fifo.vtk");
        std::filesystem::remove(fifo);
        ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
        const std::string errFile = dir() + "/stderr.txt";
        const pid_t pid = spawnCli(args, errFile);
        ASSERT_NE(pid, 0);
        waitUntilCatches(pid, SIGTERM);
        const auto signalled = std::chrono::steady_clock::now();
        ASSERT_EQ(::kill(pid, SIGTERM), 0);
        ASSERT_EQ(::kill(pid, SIGTERM), 0);
        int status = 0;
        const auto deadline = signalled + std::chrono::seconds(20);
        pid_t ended = 0;
        while ((ended = ::waitpid(pid, &status, WNOHANG)) == 0 && std::chrono::steady_clock::now() < deadline) {
            std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
        if (ended == 0) {
            ::kill(pid, SIGKILL);
            ::waitpid(pid, &status, 0);
            FAIL() << "still blocked 20 s after the signal";
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
        EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << "status " << status;
        EXPECT_GE(seconds, 1.5);
        EXPECT_LT(seconds, 10.0);
        EXPECT_TRUE(listDir(dir() + "/out").empty());
    }
}

TEST_F(CliTest, ConvertStopsOnASignalAndLeavesItsOutputAsItWas)
{
    // convert took the signals' default action: Ctrl-C while it wrote killed it and left its
    // temporary file beside OUT. Now a signal ends it with exit 130, OUT as it was. The input
    // is a FIFO, so the signal arrives (once the handler is installed, which /proc tells)
    // while convert waits for it, and the data only after.
    const std::string fifo = in("fifo.vtk");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
    writeText(out("p.ply"), "old particles\n");
    const std::string errFile = dir() + "/stderr.txt";
    const pid_t pid = spawnCli({"convert", fifo, out("p.ply")}, errFile);
    ASSERT_NE(pid, 0);
    waitUntilCatches(pid, SIGINT);
    ASSERT_EQ(::kill(pid, SIGINT), 0);
    {
        std::ofstream feed(fifo, std::ios::binary);  // opens once convert opens its end
        feed << readText(kCube);
    }
    EXPECT_EQ(waitForExit(pid), 130);
    EXPECT_EQ(readText(errFile), "nonbloppy: interrupted\n");
    EXPECT_EQ(listDir(dir() + "/out"), std::vector<std::string>{"p.ply"});
    EXPECT_EQ(readText(out("p.ply")), "old particles\n");
}

TEST_F(CliTest, ASignalWhileConvertWritesUndoesTheWrite)
{
    // A signal seen only once OUT is in place: the old OUT is put back. 400,000 particles
    // to CSV (about 7.6 MB of text) take long enough to be caught writing, which the
    // temporary file beside OUT shows; the test needs to have seen it, or it would pass
    // without the undo. A machine so fast that the write ends before the signal lands
    // gives exit 0 and the new OUT; never the new OUT with exit 130, nor a file left
    // beside it.
    nonbloppy::ParticleSet many;
    for (int n = 0; n < 400000; ++n) many.positions.emplace_back(0.001f * float(n % 1000), 0.37f * float(n), 0.5f);
    nonbloppy::writeParticles(many, in("many.xyz"));
    writeText(out("p.csv"), "old particles\n");
    const std::string errFile = dir() + "/stderr.txt";
    const pid_t pid = spawnCli({"convert", "-q", in("many.xyz"), out("p.csv")}, errFile);
    ASSERT_NE(pid, 0);
    const auto writing = [&] {
        for (const std::string& name : listDir(dir() + "/out")) {
            if (name.find(".tmp-") != std::string::npos) return true;
        }
        return false;
    };
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    bool seen = false;
    while (!(seen = writing()) && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
    ASSERT_EQ(::kill(pid, SIGINT), 0);
    int killedBy = 0;
    const int status = waitForExit(pid, &killedBy);
    ASSERT_TRUE(seen) << "the temporary file beside OUT never appeared";
    ASSERT_TRUE(status == 130 || status == 0) << status << ": " << readText(errFile);
    EXPECT_EQ(listDir(dir() + "/out"), std::vector<std::string>{"p.csv"});
    // Killed by the signal (status 130 without the handler): it landed after convert had
    // finished and put its handlers back, the new OUT complete.
    if (status == 130 && killedBy == 0) {
        EXPECT_EQ(readText(errFile), "nonbloppy: interrupted\n");
        EXPECT_EQ(readText(out("p.csv")), "old particles\n");
    } else {
        EXPECT_EQ(readText(out("p.csv")).rfind("x,y,z\n", 0), 0u);
    }
}

TEST_F(CliTest, AnOutputThatIsNotARegularFileIsRefusedBeforeAnyWork)
{
    // A FIFO (or a device, or a link to one) in place of the mesh or the .vdb: refused before
    // the input is read, and left as it was.
    ASSERT_EQ(::mkfifo(out("pipe.obj").c_str(), 0644), 0);
    ASSERT_EQ(::mkfifo(out("pipe.vdb").c_str(), 0644), 0);
    const RunResult mesh = run("mesh " + quote(kCube) + " -o " + quote(out("pipe.obj")));
    EXPECT_EQ(mesh.exitCode, 1);
    EXPECT_EQ(mesh.err, "nonbloppy: cannot write " + out("pipe.obj") + ": not a regular file\n");
    const RunResult vdb = run("mesh " + quote(kCube) + " -o " + quote(out("cube.obj")) + " --vdb " + quote(out("pipe.vdb")));
    EXPECT_EQ(vdb.exitCode, 1);
    EXPECT_EQ(vdb.err, "nonbloppy: cannot write " + out("pipe.vdb") + ": not a regular file\n");
    const RunResult convert = run("convert " + quote(kCube) + " " + quote(out("pipe.vdb")));
    EXPECT_EQ(convert.exitCode, 1);
    EXPECT_EQ(convert.err, "nonbloppy: cannot write " + out("pipe.vdb") + ": not a regular file\n");
    EXPECT_EQ(listDir(dir() + "/out"), (std::vector<std::string>{"pipe.obj", "pipe.vdb"}));
    EXPECT_TRUE(fs::is_fifo(out("pipe.obj")));
}

TEST_F(CliTest, AReportThatCannotBeWrittenIsAFailure)
{
    // 'inspect --json > info.json' on a full disk used to exit 0 with an empty file.
    if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
    const std::string errFile = dir() + "/stderr.txt";
    const auto runTo = [&](const std::string& args, const std::string& redirect) {
        const int status = std::system((quote(kCli) + " " + args + " " + redirect + " 2>" + quote(errFile)).c_str());
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    };
    EXPECT_EQ(runTo("inspect " + quote(kCube) + " --json", ">/dev/full"), 1);
    EXPECT_EQ(readText(errFile), "nonbloppy: cannot write standard output: No space left on device\n");
    EXPECT_EQ(runTo("help mesh", ">&-"), 1);
    EXPECT_EQ(readText(errFile), "nonbloppy: cannot write standard output: Bad file descriptor\n");
    // mesh and convert flush their report before they end, so the write that failed was not
    // the last one: the reason used to be lost there.
    EXPECT_EQ(runTo("mesh " + quote(kCube) + " -o " + quote(out("full.obj")), ">/dev/full"), 1);
    EXPECT_EQ(readText(errFile), "nonbloppy: cannot write standard output: No space left on device\n");
    EXPECT_TRUE(fs::exists(out("full.obj")));  // the mesh itself is whole
    EXPECT_EQ(runTo("convert " + quote(kCube) + " " + quote(out("full.ply")), ">/dev/full"), 1);
    EXPECT_EQ(readText(errFile), "nonbloppy: cannot write standard output: No space left on device\n");
    // A command that failed says why, not that its report was lost too.
    EXPECT_EQ(runTo("inspect " + quote(in("missing.vtk")), ">/dev/full"), 1);
    EXPECT_EQ(readText(errFile), "nonbloppy: cannot open " + in("missing.vtk") + ": No such file or directory\n");
    // A reader that went away ('| true' is gone before the report) asked for the rest to be
    // dropped: the mesh is written, exit 0, nothing said.
    const std::string statusFile = dir() + "/status.txt";
    ASSERT_EQ(std::system(("{ " + quote(kCli) + " mesh " + quote(kCube) + " -o " + quote(out("cube.obj")) + " 2>"
                           + quote(errFile) + "; echo $? >" + quote(statusFile) + "; } | true").c_str()), 0);
    EXPECT_EQ(readText(statusFile), "0\n");
    EXPECT_EQ(readText(errFile), "");
    EXPECT_TRUE(fs::exists(out("cube.obj")));
}

TEST_F(CliTest, VersionAndHelp)
{
    const RunResult version = run("--version");
    EXPECT_EQ(version.exitCode, 0);
    EXPECT_EQ(version.out, std::string("nonbloppy 0.1.0 (OpenVDB ") + OPENVDB_LIBRARY_VERSION_STRING
                              + ")\n");

    const RunResult help = run("--help");
    EXPECT_EQ(help.exitCode, 0);
    EXPECT_NE(help.out.find("mesh"), std::string::npos) << help.out;
    EXPECT_NE(help.out.find("inspect"), std::string::npos) << help.out;

    const RunResult meshHelp = run("mesh --help");
    EXPECT_EQ(meshHelp.exitCode, 0);
    for (const char* heading : {"Input/output", "Numerical parameters", "Advanced", "Debug"}) {
        EXPECT_NE(meshHelp.out.find(heading), std::string::npos) << heading << "\n" << meshHelp.out;
    }
    const RunResult helpMesh = run("help mesh");
    EXPECT_EQ(helpMesh.exitCode, 0);
    EXPECT_EQ(helpMesh.out, meshHelp.out);
    // "help" alone is the list of commands (it printed the usage of "help" itself).
    const RunResult bare = run("help");
    EXPECT_EQ(bare.exitCode, 0);
    EXPECT_EQ(bare.out, help.out);
    EXPECT_NE(bare.out.find("  convert "), std::string::npos) << bare.out;
    EXPECT_NE(meshHelp.out.find("--max-step"), std::string::npos) << meshHelp.out;
}
