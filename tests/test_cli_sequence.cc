// SPDX-License-Identifier: Apache-2.0
/// @file test_cli_sequence.cc
/// @brief `nonbloppy mesh` on frame sequences, run as a user would (NONBLOPPY_CLI_PATH):
///        patterns, --frames, missing frames, --skip-existing, --keep-going with a corrupt
///        frame, split ranges giving the same bytes, --frame-jobs, the --log JSON lines, an
///        interrupted run, -v's bytes per particle, and the memory a frame hands back.

#include <gtest/gtest.h>

#include "CliTestUtil.h"
#include "TestUtil.h"
#include "bench/BenchUtil.h"

#include <nonbloppy/WriteParticles.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace nonbloppy_test;

const std::string kData = NONBLOPPY_TEST_DATA_DIR;
const std::string kCube = kData + "/cube_2366_particles.vtk";
const std::string kFree = kData + "/free_particles_125_particles.vtk";

class CliSequenceTest : public CliFixture
{
protected:
    /// in/fluid_0001.vtk ... one file per source, numbered from @a first.
    void makeFrames(const std::vector<std::string>& sources, int first = 1) const
    {
        for (size_t i = 0; i < sources.size(); ++i) {
            char name[64];
            std::snprintf(name, sizeof(name), "/in/fluid_%04d.vtk", int(first + i));
            fs::copy_file(sources[i], dir() + name, fs::copy_options::overwrite_existing);
        }
    }

    /// A frame cut short in its POINTS section.
    void makeCorruptFrame(int number) const
    {
        char name[64];
        std::snprintf(name, sizeof(name), "/in/fluid_%04d.vtk", number);
        writeText(dir() + name, readText(kCube).substr(0, 300));
    }

    /// `mesh in/fluid_{}.vtk -o OUTDIR/mesh_{}.obj --vdb OUTDIR/density_####.vdb -q EXTRA`
    RunResult meshSequence(const std::string& outDir, const std::string& extra) const
    {
        fs::create_directories(outDir);
        return run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(outDir + "/mesh_{}.obj")
                   + " --vdb " + quote(outDir + "/density_####.vdb") + " " + extra);
    }
};

} // namespace

TEST_F(CliSequenceTest, MeshesEveryFrameFoundWithOneLinePerFrame)
{
    makeFrames({kFree, kCube, kFree});
    const RunResult r = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("mesh_{}.obj")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    // Frames of a different scale each: the lengths derived per frame move (said once).
    EXPECT_EQ(r.err, "nonbloppy: warning: the spacing estimate moves between frames (0.795085 in frame 1, "
                     "0.0498381 in frame 2) and the lengths derived from it move too; to mesh every frame "
                     "alike, give frame 1's: --radius 1.59017 --voxel-size 0.397542 --threshold 2.85599 "
                     "--max-step 0.397542\n");
    EXPECT_EQ(listDir(dir() + "/out"),
              (std::vector<std::string>{"mesh_0001.obj", "mesh_0002.obj", "mesh_0003.obj"}));
    // stdout is not a terminal: one line per frame, then the summary.
    const std::vector<std::string> outLines = lines(r.out);
    ASSERT_EQ(outLines.size(), 4u) << r.out;
    EXPECT_EQ(outLines[1].rfind("frame 2 (2/3): " + in("fluid_0002.vtk") + " -> "
                                + out("mesh_0002.obj") + ": 2366 particles, ", 0), 0u)
        << outLines[1];
    EXPECT_EQ(outLines[3].rfind("3 frames: 3 done, 0 failed, 0 skipped, 0 missing in ", 0), 0u)
        << outLines[3];
    // The same frame gives the same mesh.
    EXPECT_EQ(readText(out("mesh_0001.obj")), readText(out("mesh_0003.obj")));
    // The faces counted are the faces written (triangles: quads are split); it said the quads.
    size_t faces = 0;
    for (const std::string& line : lines(readText(out("mesh_0002.obj")))) faces += line.rfind("f ", 0) == 0;
    EXPECT_GT(faces, 0u);
    EXPECT_NE(outLines[1].find(" vertices, " + std::to_string(faces) + " faces, "), std::string::npos) << outLines[1];
    const RunResult quads = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("quads_{}.obj"))
                                + " --frames 2 --quads");
    ASSERT_EQ(quads.exitCode, 0) << quads.err;
    size_t polygons = 0;
    for (const std::string& line : lines(readText(out("quads_0002.obj")))) polygons += line.rfind("f ", 0) == 0;
    EXPECT_LT(polygons, faces);
    EXPECT_NE(quads.out.find(" vertices, " + std::to_string(polygons) + " faces, "), std::string::npos) << quads.out;
}

TEST_F(CliSequenceTest, AParticleBoxCropsEveryFrame)
{
    // Each frame is cropped as a single file's run is: the same mesh, and the frame's line
    // counts the particles meshed. The cube's lower half (y <= 0.35: 7 of its 14 layers).
    makeFrames({kCube, kCube});
    const std::string box = " --particle-box 0 0 0 2 0.35 2 --radius 0.1 --voxel-size 0.025";
    const RunResult sequence =
        run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("mesh_{}.ply")) + box + " --log " + quote(out("run.jsonl")));
    ASSERT_EQ(sequence.exitCode, 0) << sequence.err;
    const RunResult single = run("mesh " + quote(kCube) + " -o " + quote(out("single.ply")) + box);
    ASSERT_EQ(single.exitCode, 0) << single.err;
    EXPECT_EQ(readText(out("mesh_0001.ply")), readText(out("single.ply")));
    EXPECT_EQ(readText(out("mesh_0002.ply")), readText(out("single.ply")));
    EXPECT_NE(sequence.out.find(" -> " + out("mesh_0002.ply") + ": 1183 particles, "), std::string::npos)
        << sequence.out;
    EXPECT_NE(single.out.find("(of 2366, inside --particle-box (0, 0, 0) -> (2, 0.35, 2))"), std::string::npos)
        << single.out;
    // The log counts both: the particles meshed and those the frame's file holds.
    const std::vector<std::string> log = lines(readText(out("run.jsonl")));
    ASSERT_EQ(log.size(), 3u);  // two frames and the summary
    for (size_t frame = 0; frame < 2; ++frame) {
        EXPECT_NE(log[frame].find("\"particles\": 1183, \"particles_read\": 2366, "), std::string::npos) << log[frame];
    }
}

TEST_F(CliSequenceTest, HashAndPrintfPatterns)
{
    makeFrames({kFree, kFree}, 9);
    const RunResult r = run("mesh " + quote(in("fluid_####.vtk")) + " -o " + quote(out("m_%03d.ply"))
                            + " --vdb " + quote(out("d_{}.vdb")) + " -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_EQ(listDir(dir() + "/out"), (std::vector<std::string>{"d_0009.vdb", "d_0010.vdb",
                                                                 "m_009.ply", "m_010.ply"}));
}

TEST_F(CliSequenceTest, DirectoriesMaySpellPlaceholders)
{
    // '#', '{}' and '%d' in a directory are its name: a file in "shot#1" was refused as a
    // pattern, and a sequence there as holding two placeholders.
    const std::string shot = dir() + "/shot#1 50%d";
    fs::create_directories(shot);
    fs::copy_file(kFree, shot + "/fluid_0003.vtk");
    fs::copy_file(kFree, shot + "/fluid_0004.vtk");
    RunResult r = run("mesh " + quote(shot + "/fluid_0003.vtk") + " -o " + quote(shot + "/single.ply")
                      + " --vdb " + quote(shot + "/single.vdb") + " -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    r = run("mesh " + quote(shot + "/fluid_{}.vtk") + " -o " + quote(shot + "/m_#.obj") + " -q");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(listDir(shot), (std::vector<std::string>{"fluid_0003.vtk", "fluid_0004.vtk", "m_3.obj", "m_4.obj",
                                                       "single.ply", "single.vdb"}));

    // A file missing from such a directory is missing, not a pattern.
    r = run("mesh " + quote(shot + "/gone.vtk") + " -o " + quote(shot + "/gone.ply"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "nonbloppy: cannot open " + shot + "/gone.vtk: No such file or directory\n");
    // Only a directory spelling one names no file, and frames are files: refused as before.
    r = run("mesh " + quote(dir() + "/take_{}/fluid.vtk") + " -o " + quote(out("m.obj")));
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_EQ(r.err, "nonbloppy: IN: the frame placeholder must be in the file name, not in a directory ('" + dir()
                         + "/take_{}/fluid.vtk')\n");
    makeFrames({kFree});
    r = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("m_{}/mesh.obj")));
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_EQ(r.err, "nonbloppy: --output: the frame placeholder must be in the file name, not in a directory ('"
                         + out("m_{}/mesh.obj") + "')\n");
    EXPECT_TRUE(listDir(dir() + "/out").empty());
}

TEST_F(CliSequenceTest, OutputWithoutPlaceholderIsAnError)
{
    makeFrames({kFree});
    for (const std::string& extra : {std::string(""), " --vdb " + quote(out("d.vdb"))}) {
        const std::string output = extra.empty() ? out("mesh.obj") : out("mesh_{}.obj");
        const RunResult r = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(output) + extra);
        EXPECT_EQ(r.exitCode, 2);
        const std::string option = extra.empty() ? "--output" : "--vdb";
        const std::string path = extra.empty() ? output : out("d.vdb");
        EXPECT_EQ(r.err, "nonbloppy: " + option + ": no frame placeholder ({}, #### or %04d) in '"
                             + path + "', but IN is the sequence '" + in("fluid_{}.vtk") + "'\n");
        EXPECT_TRUE(listDir(dir() + "/out").empty());
    }
}

TEST_F(CliSequenceTest, LogNamingAnInputFrameOrAnOutputIsRefusedBeforeAnyWork)
{
    makeFrames({kFree, kFree});
    const std::string frame2 = in("fluid_0002.vtk");
    const std::string before = readText(frame2);
    // Written first, the log would have replaced frame 2 with JSON.
    expectUsageError("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("mesh_{}.obj")) + " --log ''",
                     "--log needs a file name, got ''");
    expectUsageError("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("mesh_{}.obj")) + " --log "
                      + quote(frame2),
                  "cannot write " + frame2 + ": --log names the input of frame 2");
    EXPECT_EQ(readText(frame2), before);
    // Frame 1's rename would have replaced the log.
    expectUsageError("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("mesh_{}.obj")) + " --vdb "
                      + quote(out("density_{}.vdb")) + " --log " + quote(out("density_0001.vdb")),
                  "cannot write " + out("density_0001.vdb") + ": --log names an output of frame 1");
}

TEST_F(CliSequenceTest, NoFrameWritesAnotherFramesInputOrTheLog)
{
    // Frame 1's mesh in/fluid_11.vtk would have replaced frame 11's particles, and then been
    // read as them: the output was only compared with its own frame's input.
    fs::copy_file(kFree, in("fluid_1.vtk"));
    fs::copy_file(kCube, in("fluid_11.vtk"));
    const std::string frame11 = in("fluid_11.vtk");
    const std::string before = readText(frame11);
    const std::string pattern = "mesh " + quote(in("fluid_{}.vtk")) + " ";
    expectUsageError(pattern + "-o " + quote(in("fluid_1{}.vtk")), "cannot write " + frame11 + ": it is the input of frame 11");
    // Also when frame 11 is not among the requested frames, and for the log.
    expectUsageError(pattern + "--frames 1 -o " + quote(in("fluid_1{}.vtk")),
                     "cannot write " + frame11 + ": it is the input of frame 11");
    expectUsageError(pattern + "--frames 1 -o " + quote(out("m_{}.obj")) + " --log " + quote(frame11),
                     "cannot write " + frame11 + ": --log names the input of frame 11");
    EXPECT_EQ(readText(frame11), before);
    // A log spelled differently from the output it names ("./" inside the path).
    const std::string dotted = dir() + "/out/./m_11.obj";
    expectUsageError(pattern + "-o " + quote(out("m_{}.obj")) + " --log " + quote(dotted),
                     "cannot write " + dotted + ": --log names an output of frame 11");
}

TEST_F(CliSequenceTest, NoOutputIsNamedSoTheInputPatternWouldReadItAsAFrame)
{
    // 'f_{}.vtk' -o 'f_####.vtk' wrote frame 7's mesh as f_0007.vtk beside the particles
    // f_007.vtk: every later run of the pattern stopped at "both frame 7". Refused before
    // anything is written, the same from another spelling of the directory.
    fs::copy_file(kCube, in("f_007.vtk"));
    const std::string before = readText(in("f_007.vtk"));
    expectUsageError("mesh " + quote(in("f_{}.vtk")) + " -o " + quote(in("f_####.vtk")),
                     "cannot write " + in("f_0007.vtk") + ": " + in("f_{}.vtk") + " would read it as frame 7");
    const std::string dotted = dir() + "/in/./f_%05d.vtk";
    expectUsageError("mesh " + quote(in("f_{}.vtk")) + " -o " + quote(dotted),
                     "cannot write " + dir() + "/in/./f_00007.vtk: " + in("f_{}.vtk") + " would read it as frame 7");
    EXPECT_EQ(listDir(dir() + "/in"), (std::vector<std::string>{"f_007.vtk"}));
    EXPECT_EQ(readText(in("f_007.vtk")), before);
    // A name the pattern does not read, or another directory, is fine.
    for (const std::string& output : {in("f_####_mesh.vtk"), out("f_####.vtk")}) {
        const RunResult r = run("mesh -q " + quote(in("f_{}.vtk")) + " -o " + quote(output));
        EXPECT_EQ(r.exitCode, 0) << output << ": " << r.err;
    }
}

TEST_F(CliSequenceTest, SequenceOptionsNeedASequence)
{
    const RunResult r = run("mesh " + quote(kFree) + " -o " + quote(out("m.obj")) + " --frames 1-3");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_EQ(r.err, "nonbloppy: --frames needs a frame sequence as IN (a name with {}, #### or "
                     "%04d), got '" + kFree + "'\n");
    EXPECT_TRUE(listDir(dir() + "/out").empty());
    // So do the options that only a run over frames has a use for.
    for (const std::string option : {"--skip-existing", "--keep-going", "--frame-jobs 2", "--log"}) {
        const std::string extra = option == "--log" ? " " + quote(dir() + "/run.jsonl") : "";
        expectUsageError("mesh " + quote(kFree) + " -o " + quote(out("m.obj")) + " " + option + extra,
                         option.substr(0, option.find(' ')) + " needs a frame sequence as IN (a name with {}, "
                         "#### or %04d), got '" + kFree + "'");
    }
    EXPECT_FALSE(fs::exists(dir() + "/run.jsonl"));
    // And outputs named for a sequence: a file literally named 'm_{}.obj' was written.
    expectUsageError("mesh " + quote(kFree) + " -o " + quote(out("m_{}.obj")),
                     "--output: a frame placeholder ({}, #### or %04d) in '" + out("m_{}.obj")
                         + "', but IN is the single file '" + kFree + "'");
    expectUsageError("mesh " + quote(kFree) + " -o " + quote(out("m.obj")) + " --vdb " + quote(out("g_####.vdb")),
                     "--vdb: a frame placeholder ({}, #### or %04d) in '" + out("g_####.vdb")
                         + "', but IN is the single file '" + kFree + "'");
    // An empty --vdb (a variable left unset) wrote no grid without a word.
    expectUsageError("mesh " + quote(kFree) + " -o " + quote(out("m.obj")) + " --vdb ''",
                     "--vdb needs a file name, got ''");
}

TEST_F(CliSequenceTest, FramesSelectsAndListsMissingOnce)
{
    makeFrames({kFree, kFree, kFree});
    const RunResult r = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("m_{}.obj"))
                            + " --frames 1-7:2");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "nonbloppy: 2 missing frames skipped: 5, 7 (" + in("fluid_{}.vtk") + ")\n");
    EXPECT_EQ(listDir(dir() + "/out"), (std::vector<std::string>{"m_0001.obj", "m_0003.obj"}));
    EXPECT_NE(r.out.find("4 frames: 2 done, 0 failed, 0 skipped, 2 missing"), std::string::npos)
        << r.out;

    // -q: the notice (not an error) is left to the summary and the log.
    const RunResult quiet = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("q_{}.obj")) +
                                " --frames 1-7:2 -q");
    EXPECT_EQ(quiet.exitCode, 0);
    EXPECT_EQ(quiet.err, "");

    const RunResult none = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("m_{}.obj"))
                               + " --frames 20-21");
    EXPECT_EQ(none.exitCode, 1);
    EXPECT_EQ(none.err, "nonbloppy: none of the frames 20-21 of " + in("fluid_{}.vtk") + " exist\n");
}

TEST_F(CliSequenceTest, BadFramesIsAOneLineError)
{
    makeFrames({kFree});
    const std::string base = "mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("m_{}.obj"));
    for (const auto& [frames, message] : std::vector<std::pair<std::string, std::string>>{
             {"12-3", "--frames: bad range '12-3' (end before start)"},
             {"1-9:0", "--frames: bad step in '1-9:0' (must be an integer >= 1)"},
             {"1,,2", "--frames: empty item in '1,,2'"}}) {
        const RunResult r = run(base + " --frames " + quote(frames));
        EXPECT_EQ(r.exitCode, 2);
        EXPECT_EQ(r.err, "nonbloppy: " + message + "\n");
    }
    const RunResult jobs = run(base + " --frame-jobs 0");
    EXPECT_EQ(jobs.exitCode, 2);
    EXPECT_EQ(jobs.err, "nonbloppy: --frame-jobs must be >= 1, got 0\n");
    // No file to mesh is not a bad command line: a frame failed to appear (exit 1).
    const RunResult noFiles = run("mesh " + quote(in("gas_{}.vtk")) + " -o " + quote(out("m_{}.obj")));
    EXPECT_EQ(noFiles.exitCode, 1);
    EXPECT_EQ(noFiles.err, "nonbloppy: no file matches " + in("gas_{}.vtk") + "\n");
    EXPECT_TRUE(listDir(dir() + "/out").empty());
}

TEST_F(CliSequenceTest, SkipExistingResumes)
{
    makeFrames({kFree, kFree, kFree});
    ASSERT_EQ(meshSequence(dir() + "/out", "--frames 1-2").exitCode, 0);
    // A finished frame is kept as it is, even if it was changed since.
    writeText(out("mesh_0001.obj"), "# kept\n");
    const RunResult r = meshSequence(dir() + "/out", "--skip-existing --log " + quote(dir() + "/run.jsonl"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(readText(out("mesh_0001.obj")), "# kept\n");
    EXPECT_EQ(listDir(dir() + "/out").size(), 6u);
    const std::string log = readText(dir() + "/run.jsonl");
    EXPECT_EQ(count(log, "\"status\": \"skipped\""), 2u) << log;
    EXPECT_EQ(count(log, "\"status\": \"done\""), 1u) << log;
    // Skipped on all its outputs, the mesh and the .vdb (it named the mesh alone).
    EXPECT_NE(r.out.find("skipped, its 2 outputs exist"), std::string::npos) << r.out;

    // A frame with only some of its outputs (the mesh, not the .vdb) is made again, all of it.
    fs::remove(out("density_0002.vdb"));
    writeText(out("mesh_0002.obj"), "# stale\n");
    const RunResult partial = meshSequence(dir() + "/out", "--skip-existing --log " + quote(dir() + "/partial.jsonl"));
    ASSERT_EQ(partial.exitCode, 0) << partial.err;
    const std::vector<std::string> logLines = lines(readText(dir() + "/partial.jsonl"));
    ASSERT_EQ(logLines.size(), 4u);  // three frames and the summary
    EXPECT_EQ(logLines[0].rfind("{\"frame\": 1, \"status\": \"skipped\"", 0), 0u) << logLines[0];
    EXPECT_EQ(logLines[1].rfind("{\"frame\": 2, \"status\": \"done\"", 0), 0u) << logLines[1];
    EXPECT_EQ(logLines[2].rfind("{\"frame\": 3, \"status\": \"skipped\"", 0), 0u) << logLines[2];
    EXPECT_TRUE(fs::exists(out("density_0002.vdb")));
    EXPECT_NE(readText(out("mesh_0002.obj")), "# stale\n");
    EXPECT_EQ(listDir(dir() + "/out").size(), 6u);

    // Without --skip-existing every frame is made again.
    ASSERT_EQ(meshSequence(dir() + "/out", "").exitCode, 0);
    EXPECT_NE(readText(out("mesh_0001.obj")), "# kept\n");
}

TEST_F(CliSequenceTest, FramesMadeAgainLeaveNoLinkToTheFilesTheyReplaced)
{
    // Each frame's replaced outputs are unlinked on the remover's thread while the next
    // frames run; the run must not end before they are gone.
    makeFrames({kCube, kFree, kCube, kFree});
    for (const char* jobs : {"--frame-jobs 1", "--frame-jobs 2"}) {
        SCOPED_TRACE(jobs);
        ASSERT_EQ(meshSequence(dir() + "/out", std::string("-q -c 0.1 ") + jobs).exitCode, 0);
        const std::string before = readText(out("mesh_0003.obj"));
        ASSERT_EQ(meshSequence(dir() + "/out", std::string("-q -c 0.5 ") + jobs).exitCode, 0);
        EXPECT_EQ(listDir(dir() + "/out"),
                  (std::vector<std::string>{"density_0001.vdb", "density_0002.vdb", "density_0003.vdb",
                                            "density_0004.vdb", "mesh_0001.obj", "mesh_0002.obj",
                                            "mesh_0003.obj", "mesh_0004.obj"}));
        EXPECT_NE(readText(out("mesh_0003.obj")), before);
    }
}

TEST_F(CliSequenceTest, FirstBadFrameStopsTheRun)
{
    makeFrames({kFree, kFree, kFree});
    makeCorruptFrame(2);
    const RunResult r = meshSequence(dir() + "/out", "");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "nonbloppy: frame 2: truncated POINTS section (" + in("fluid_0002.vtk") + ")\n");
    EXPECT_EQ(listDir(dir() + "/out"), (std::vector<std::string>{"density_0001.vdb", "mesh_0001.obj"}));
    // Frame 3 never started; the summary still adds up to the 3 frames.
    EXPECT_NE(r.out.find("3 frames: 1 done, 1 failed, 0 skipped, 0 missing, 1 not run in "), std::string::npos)
        << r.out;
}

TEST_F(CliSequenceTest, AFrameWhoseWriteFailsIsThatFrameFailing)
{
    // A frame is written while the next one is meshed. A 2 MB file-size limit (SIGXFSZ
    // ignored) stands in for a full disk: the dam break's OBJ (8.2 MB) fails, the cubes'
    // (0.85 MB) fit. The failure is frame 2's, reported in frame order; frame 3, meshed
    // meanwhile, is not written unless --keep-going.
    makeFrames({kCube, kData + "/dam_break_frame_23_24389_particles.vtk", kCube});
    const auto meshLimited = [&](const std::string& extra) {
        const std::string command = "trap '' XFSZ; ulimit -f 2048; exec " + quote(kCli) + " mesh " +
                                    quote(in("fluid_{}.vtk")) + " -o " + quote(out("mesh_{}.obj")) + " -q " + extra;
        const std::string errFile = dir() + "/stderr.txt";
        const int status = std::system(("bash -c " + quote(command) + " >/dev/null 2>" + quote(errFile)).c_str());
        RunResult result;
        result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        result.err = readText(errFile);
        return result;
    };
    const std::string message = "nonbloppy: frame 2: cannot write " + out("mesh_0002.obj") + ": File too large";
    RunResult r = meshLimited("--log " + quote(dir() + "/run.jsonl"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(lines(r.err), std::vector<std::string>{message});
    EXPECT_EQ(listDir(dir() + "/out"), std::vector<std::string>{"mesh_0001.obj"});
    const std::string log = readText(dir() + "/run.jsonl");
    EXPECT_NE(log.find("\"frames_done\": 1, \"frames_failed\": 1, "), std::string::npos) << log;
    EXPECT_NE(log.find("\"frames_not_run\": 1, \"failed\": [2]"), std::string::npos) << log;

    fs::remove(out("mesh_0001.obj"));
    r = meshLimited("--keep-going");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(lines(r.err), (std::vector<std::string>{message, "nonbloppy: 1 of 3 frames failed: 2"}));
    EXPECT_EQ(listDir(dir() + "/out"), (std::vector<std::string>{"mesh_0001.obj", "mesh_0003.obj"}));
}

TEST_F(CliSequenceTest, ParametersThatDoNotSuitAFrameFailThatFrame)
{
    // A frame of one particle has no spacing to derive the parameters from: the library's
    // ParameterError. In a sequence that is a failed frame (exit 1, named), not a bad
    // command line (exit 2): the same command meshes the other frames.
    makeFrames({kFree, kFree});
    writeText(in("fluid_0002.vtk"), "# vtk DataFile Version 3.0\none\nASCII\nDATASET POLYDATA\n"
                                   "POINTS 1 float\n0 0 0\n");
    const std::string message = "cannot estimate the particle spacing from 1 particle; give --spacing or "
                                "--radius, --threshold and --voxel-size";
    const RunResult r = meshSequence(dir() + "/out", "-q");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "nonbloppy: frame 2: " + in("fluid_0002.vtk") + ": " + message + "\n");
    EXPECT_TRUE(fs::exists(dir() + "/out/mesh_0001.obj")) << "frame 1 is meshed";
    EXPECT_FALSE(fs::exists(dir() + "/out/mesh_0002.obj"));
    const RunResult single = run("mesh " + quote(in("fluid_0002.vtk")) + " -o " + quote(out("one.obj")));
    EXPECT_EQ(single.exitCode, 1);
    EXPECT_EQ(single.err, "nonbloppy: " + in("fluid_0002.vtk") + ": " + message + "\n");
}

TEST_F(CliSequenceTest, KeepGoingListsFailedFrames)
{
    makeFrames({kFree, kFree, kFree, kFree});
    makeCorruptFrame(2);
    const RunResult r = meshSequence(dir() + "/out", "--keep-going --log " + quote(dir() + "/run.jsonl"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(lines(r.err), (std::vector<std::string>{
        "nonbloppy: frame 2: truncated POINTS section (" + in("fluid_0002.vtk") + ")",
        "nonbloppy: 1 of 4 frames failed: 2"}));
    EXPECT_EQ(listDir(dir() + "/out"),
              (std::vector<std::string>{"density_0001.vdb", "density_0003.vdb", "density_0004.vdb",
                                        "mesh_0001.obj", "mesh_0003.obj", "mesh_0004.obj"}));
    const std::string log = readText(dir() + "/run.jsonl");
    EXPECT_NE(log.find("\"frame\": 2, \"status\": \"failed\""), std::string::npos) << log;
    EXPECT_NE(log.find("\"frames_failed\": 1, "), std::string::npos) << log;
    EXPECT_NE(log.find("\"failed\": [2]"), std::string::npos) << log;
}

TEST_F(CliSequenceTest, ALogThatCannotBeWrittenIsSaidAtOnceAndFailsTheRunAtItsEnd)
{
    // /dev/full fails every write with ENOSPC, as a full disk. Before, the run said nothing
    // until its end, and then only "cannot write /dev/full", without the cause.
    if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
    makeFrames({kFree, kFree, kFree});
    const RunResult r = meshSequence(dir() + "/out", "--log /dev/full");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(lines(r.err), (std::vector<std::string>{
        "nonbloppy: warning: cannot write /dev/full: No space left on device; the log stops here, the frames go on",
        "nonbloppy: cannot write /dev/full: No space left on device"}));
    // The frames went on: every mesh is there, and each frame and the summary were printed.
    EXPECT_EQ(listDir(dir() + "/out"),
              (std::vector<std::string>{"density_0001.vdb", "density_0002.vdb", "density_0003.vdb",
                                        "mesh_0001.obj", "mesh_0002.obj", "mesh_0003.obj"}));
    EXPECT_EQ(lines(r.out).size(), 4u) << r.out;
}

TEST_F(CliSequenceTest, ARunWithoutFramesReplacesAnEarlierLog)
{
    // A resubmitted farm task that found none of its frames left the earlier attempt's log,
    // which monitoring then read as this attempt's result.
    makeFrames({kFree});
    const std::string log = out("run.jsonl");
    writeText(log, "{\"summary\": true, \"frames_done\": 1}\n");
    const std::string base = "mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("m_{}.obj"));
    const RunResult r = run(base + " --frames 5 --log " + quote(log));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.err, "nonbloppy: none of the frames 5 of " + in("fluid_{}.vtk") + " exist\n");
    EXPECT_EQ(readText(log), "{\"summary\": true, \"input\": " + ("\"" + in("fluid_{}.vtk") + "\"") +
                                 ", \"output\": " + ("\"" + out("m_{}.obj") + "\"") +
                                 ", \"frames_done\": 0, \"error\": \"none of the frames 5 of " +
                                 in("fluid_{}.vtk") + " exist\"}\n");
    // Never over an input of the sequence, even one not asked for.
    const std::string frame1 = in("fluid_0001.vtk"), before = readText(frame1);
    EXPECT_EQ(run(base + " --frames 5 --log " + quote(frame1)).exitCode, 1);
    EXPECT_EQ(readText(frame1), before);
    // Nor when the frames exist but the outputs are refused before the first one (bug hunt:
    // the earlier log was left): a missing directory, an output that is an input.
    writeText(log, "{\"summary\": true, \"frames_done\": 1}\n");
    const std::string missing = "mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("nodir/m_{}.obj"));
    const RunResult refused = run(missing + " --log " + quote(log));
    EXPECT_EQ(refused.exitCode, 1);
    EXPECT_EQ(refused.err, "nonbloppy: cannot write " + out("nodir/m_0001.obj") + ": No such file or directory\n");
    EXPECT_NE(readText(log).find("\"frames_done\": 0, \"error\": \"cannot write " + out("nodir/m_0001.obj")),
              std::string::npos) << readText(log);
    writeText(log, "{\"summary\": true, \"frames_done\": 1}\n");
    const RunResult clash = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(in("fluid_{}.vtk")) + " --log " + quote(log));
    EXPECT_EQ(clash.exitCode, 2);
    EXPECT_NE(readText(log).find("\"frames_done\": 0"), std::string::npos) << readText(log);
    // Nor as a frame the input pattern would read, even when the run is refused for another
    // reason (review: the log became frame 9, and the next run failed on it).
    EXPECT_EQ(run(missing + " --log " + quote(in("fluid_0009.vtk"))).exitCode, 1);
    EXPECT_FALSE(fs::exists(in("fluid_0009.vtk")));
    const RunResult asFrame = run(base + " --log " + quote(in("fluid_0009.vtk")));
    EXPECT_EQ(asFrame.exitCode, 2);
    EXPECT_EQ(asFrame.err, "nonbloppy: cannot write " + in("fluid_0009.vtk") + ": " + in("fluid_{}.vtk") +
                               " would read it as frame 9\n");
    EXPECT_FALSE(fs::exists(in("fluid_0009.vtk")));
    // ... but not over an output: its rename would replace the log, and the run is refused.
    const std::string mesh1 = out("m_0001.obj");
    writeText(mesh1, "earlier mesh\n");
    EXPECT_EQ(run(base + " --log " + quote(mesh1)).exitCode, 2);
    EXPECT_EQ(readText(mesh1), "earlier mesh\n");
}

TEST_F(CliSequenceTest, OnATerminalWarningsEraseTheBarAndVerboseRunsDrawNone)
{
    // A warning (stderr) ran on after the bar (stdout) on the same terminal, and so did -v's
    // progress lines (bug hunt). script(1) gives the run a terminal for both.
    if (std::system("command -v script >/dev/null 2>&1") != 0) GTEST_SKIP() << "no script(1)";
    makeFrames({kFree, kCube, kFree});
    const std::string transcript = out("terminal.txt");
    const auto onTerminal = [&](const std::string& options) {
        const std::string command = quote(kCli) + " mesh " + quote(in("fluid_{}.vtk")) + " -o " +
                                    quote(out("m_{}.obj")) + options;
        const std::string shell = "script -qec " + quote(command) + " /dev/null >" + quote(transcript) + " 2>&1 </dev/null";
        EXPECT_EQ(std::system(shell.c_str()), 0) << shell;
        return readText(transcript);
    };
    const std::string barred = onTerminal("");
    EXPECT_NE(barred.find("] 3/3 frames"), std::string::npos) << barred;
    // Each warning starts its own line: nothing before it there, or a bar erased ("\r\033[K").
    size_t warnings = 0;
    for (size_t at = barred.find("nonbloppy: warning: "); at != std::string::npos;
         at = barred.find("nonbloppy: warning: ", at + 1), ++warnings) {
        const size_t lineStart = at == 0 ? 0 : barred.rfind('\n', at - 1) + 1;  // npos + 1 == 0
        const std::string before = barred.substr(lineStart, at - lineStart);
        EXPECT_TRUE(before.empty() || before == "\r" ||
                    (before.size() >= 4 && before.compare(before.size() - 4, 4, "\r\033[K") == 0))
            << before << "\n" << barred;
    }
    EXPECT_EQ(warnings, 1u) << barred;  // the spacing estimate moves
    const std::string verbose = onTerminal(" -v");
    EXPECT_EQ(verbose.find("] 1/3 frames"), std::string::npos) << verbose;
    EXPECT_NE(verbose.find("frame 3 (3/3): "), std::string::npos) << verbose;
    EXPECT_NE(verbose.find("[progress] frame 2: extract surface done"), std::string::npos) << verbose;
}

TEST_F(CliSequenceTest, EveryCountIsOfTheFramesAskedFor)
{
    // stdout said "5 frames", the failure "2 of 3 frames failed" and the log "frames": 3.
    makeCorruptFrame(1);
    makeCorruptFrame(2);
    makeFrames({kFree}, 4);
    const std::string log = out("run.jsonl");
    const RunResult r = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("m_{}.obj")) +
                            " --keep-going --frames 1-5 --log " + quote(log));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.out.find("5 frames: 1 done, 2 failed, 0 skipped, 2 missing in "), std::string::npos) << r.out;
    EXPECT_EQ(lines(r.err).back(), "nonbloppy: 2 of 5 frames failed: 1-2");
    const std::string summary = lines(readText(log)).back();
    EXPECT_NE(summary.find("\"frames\": 5, \"frames_done\": 1, \"frames_failed\": 2, \"frames_skipped\": 0, "
                           "\"frames_missing\": 2, \"frames_interrupted\": 0, \"frames_not_run\": 0"),
              std::string::npos) << summary;
}

TEST_F(CliSequenceTest, SplitRangesGiveTheSameFiles)
{
    makeFrames({kFree, kCube, kFree, kFree});
    ASSERT_EQ(meshSequence(dir() + "/whole", "-q --frames 1-4").exitCode, 0);
    ASSERT_EQ(meshSequence(dir() + "/split", "-q --frames 1-2").exitCode, 0);
    ASSERT_EQ(meshSequence(dir() + "/split", "-q --frames 3-4").exitCode, 0);
    ASSERT_EQ(meshSequence(dir() + "/jobs", "-q --frame-jobs 3 --threads 2").exitCode, 0);
    const std::vector<std::string> names = listDir(dir() + "/whole");
    ASSERT_EQ(names.size(), 8u);
    for (const char* other : {"/split", "/jobs"}) {
        ASSERT_EQ(listDir(dir() + other), names) << other;
        for (const std::string& name : names) {
            EXPECT_TRUE(readText(dir() + "/whole/" + name) == readText(dir() + other + "/" + name))
                << other << "/" << name << " differs";
        }
    }
}

/// The number after "@a key": in a --log line; -1 if the line has no such key.
double numberAfter(const std::string& line, const std::string& key)
{
    const std::string marker = "\"" + key + "\": ";
    const size_t at = line.find(marker);
    return at == std::string::npos ? -1.0 : std::strtod(line.c_str() + at + marker.size(), nullptr);
}

TEST_F(CliSequenceTest, LogHasOneObjectPerFrameAndASummary)
{
    makeFrames({kCube, kCube});
    const std::string logPath = dir() + "/run.jsonl";
    const RunResult r = meshSequence(dir() + "/out", "-q --log " + quote(logPath) + " --radius 0.1");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::vector<std::string> logLines = lines(readText(logPath));
    ASSERT_EQ(logLines.size(), 3u);
    const std::string& frame2 = logLines[1];
    for (const std::string& field :
         {"{\"frame\": 2, \"status\": \"done\", \"input\": \"" + in("fluid_0002.vtk") + "\"",
          "\"output\": \"" + dir() + "/out/mesh_0002.obj\"",
          "\"outputs\": [\"" + dir() + "/out/mesh_0002.obj\", \"" + dir() + "/out/density_0002.vdb\"]",
          std::string("\"particles\": 2366, "), std::string("\"vertices\": "),
          std::string("\"faces\": "), std::string("\"seconds\": {\"read particles\": "),
          std::string("\"rasterize density\": "), std::string("\"write vdb\": "),
          std::string("\"peak_rss_bytes\": "), std::string("\"parameters\": {\"spacing\": "),
          std::string("\"effective_radius\": 0.1, "), std::string("\"iterations\": 2, "),
          std::string("\"region_leaves\": 1024, \"max_step\": 0.0249190720783451")}) {
        EXPECT_NE(frame2.find(field), std::string::npos) << field << "\n" << frame2;
    }
    EXPECT_EQ(frame2.back(), '}');
    // CPU seconds: a frame's, over its stages, and the whole process's in the summary,
    // which holds each frame's (and the start, and the writing of the log). Not their sum: the
    // first frame's files are written while the second frame runs, and the CPU time of that
    // overlap counts in both frames (CI saw the sum exceed the summary by 49 us).
    const double frame1Cpu = numberAfter(logLines[0], "cpu_seconds"), frame2Cpu = numberAfter(frame2, "cpu_seconds");
    EXPECT_GT(frame1Cpu, 0.0) << logLines[0];
    EXPECT_GT(frame2Cpu, 0.0) << frame2;
    EXPECT_GE(numberAfter(logLines[2], "cpu_seconds"), std::max(frame1Cpu, frame2Cpu)) << logLines[2];
    const std::string& summary = logLines[2];
    for (const char* field : {"{\"summary\": true, ", "\"frames_done\": 2, ", "\"frames_failed\": 0, ",
                              "\"frames_skipped\": 0, ", "\"frames_missing\": 0, ",
                              "\"interrupted\": false", "\"total_seconds\": ",
                              "\"particles\": 4732, ", "\"particles_per_second\": ", "\"frame_jobs\": 1, \"threads\": "}) {
        EXPECT_NE(summary.find(field), std::string::npos) << field << "\n" << summary;
    }
}

TEST_F(CliSequenceTest, AReaderOfStdoutThatGoesAwayDoesNotEndTheRun)
{
    // A reader that stops reading (here at once; "| head -1" alike) used to kill the run with
    // SIGPIPE (exit 141): frames unmeshed, the log without its summary.
    makeFrames({kFree, kFree, kFree});
    const std::string log = out("run.jsonl");
    const std::string command = "set -o pipefail; " + quote(kCli) + " mesh " + quote(in("fluid_{}.vtk")) + " -o " +
                                quote(out("mesh_{}.obj")) + " --log " + quote(log) + " | true";
    const int status = std::system(("bash -c " + quote(command)).c_str());
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
    for (const char* mesh : {"mesh_0001.obj", "mesh_0002.obj", "mesh_0003.obj"}) EXPECT_TRUE(fs::exists(out(mesh))) << mesh;
    const std::vector<std::string> logLines = lines(readText(log));
    ASSERT_EQ(logLines.size(), 4u);
    EXPECT_NE(logLines.back().find("\"frames_done\": 3"), std::string::npos) << logLines.back();
}

TEST_F(CliSequenceTest, InterruptedRunLeavesNoPartialFile)
{
    // Frame 1 is quick; frame 2, the dam break on a fine grid, takes long enough to be caught.
    makeFrames({kCube, kData + "/dam_break_frame_23_24389_particles.vtk", kCube});
    // Interrupt once the second frame's density is being computed.
    const RunResult r = interruptWhen(
        {"mesh", in("fluid_{}.vtk"), "-o", out("mesh_{}.obj"), "--vdb", out("d_{}.vdb"),
         "--voxel-size", "0.005", "-v", "--log", dir() + "/run.jsonl"},
        [](const std::string& err) { return count(err, "[progress] frame 2: rasterize density ...") >= 1; },
        SIGTERM);
    ASSERT_EQ(r.killedBy, 0) << "killed by the signal instead of handling it";
    EXPECT_EQ(r.exitCode, 130);
    const std::vector<std::string> errLines = lines(r.err);
    ASSERT_FALSE(errLines.empty());
    EXPECT_EQ(errLines.back(), "nonbloppy: interrupted; finished frames: 1 (1 of 3)");
    EXPECT_EQ(listDir(dir() + "/out"), (std::vector<std::string>{"d_0001.vdb", "mesh_0001.obj"}));
    const std::string log = readText(dir() + "/run.jsonl");
    EXPECT_NE(log.find("\"interrupted\": true"), std::string::npos) << log;
    EXPECT_NE(log.find("\"frames_done\": 1, "), std::string::npos) << log;
    // Frame 2, cut short, is logged and counted as interrupted; frame 3 was never started. Its
    // stage is reported stopped, not done.
    EXPECT_NE(log.find("{\"frame\": 2, \"status\": \"interrupted\""), std::string::npos) << log;
    EXPECT_NE(log.find("\"frames_interrupted\": 1, \"frames_not_run\": 1, "), std::string::npos) << log;
    EXPECT_NE(r.err.find("[progress] frame 2: rasterize density stopped ("), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("[progress] frame 2: rasterize density done"), std::string::npos) << r.err;
}

TEST_F(CliSequenceTest, VerboseProgressLinesNameTheirFrameAndStayWhole)
{
    // With --frame-jobs 2 the frames' lines interleaved mid-line ("[progress] [progress]
    // rasterize density 75%") and none named its frame.
    makeFrames({kCube, kCube, kCube, kCube});
    const RunResult r = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("mesh_{}.obj")) +
                            " -v --frame-jobs 2");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    size_t progressLines = 0;
    for (const std::string& line : lines(r.err)) {
        if (line.rfind("[progress]", 0) != 0) continue;
        ++progressLines;
        EXPECT_EQ(count(line, "[progress]"), 1u) << line;
        EXPECT_EQ(line.rfind("[progress] frame ", 0), 0u) << line;
    }
    EXPECT_GE(progressLines, 4u * 2u * 8u);  // a start and an end line per stage and frame
    for (const char* frame : {"1", "2", "3", "4"}) {
        EXPECT_EQ(count(r.err, std::string("[progress] frame ") + frame + ": read particles ..."), 1u) << frame;
    }
}

TEST_F(CliSequenceTest, VerbosePrintsBytesPerParticle)
{
    const RunResult r = run("mesh " + quote(kCube) + " -o " + quote(out("cube.obj")) + " -v");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* stage : {"read particles", "rasterize density", "relax vertices", "write mesh"}) {
        const size_t at = r.err.find("[memory]   " + std::string(stage));
        ASSERT_NE(at, std::string::npos) << stage << "\n" << r.err;
        EXPECT_NE(r.err.find("bytes/particle", at), std::string::npos) << r.err;
    }
    EXPECT_NE(r.err.find("getrusage ru_maxrss"), std::string::npos) << r.err;
}

TEST_F(CliSequenceTest, ASequencePeaksNoHigherAfterItsSecondFrame)
{
#ifdef NONBLOPPY_TEST_ASAN
    GTEST_SKIP() << "AddressSanitizer keeps freed memory in quarantine";
#endif
    // Four frames of eight disjoint copies of the dam-break frame (195,112 particles; the
    // benchmarks' tiledFrame()). glibc kept what a frame freed, and the next frame reused it
    // only in part: a 64x frame's peak rose 328 -> 440 MB by the third frame, so a farm job
    // sized by meshing one frame could be killed mid-sequence. Each frame's memory is handed
    // back once it is written (while the next frame is meshed), and the writes' buffers are
    // not kept in the writing thread's malloc arena (SystemBuffer.h). Here, one frame alone:
    // 108-113 MiB; three: 115-125 (133-148 while that arena kept them, 161-170 without
    // handing memory back).
    // Compared with the peak when the second frame is done, not with a run of one frame:
    // from the second frame on, each is meshed while the one before is written, and a slow
    // disk keeps the frame before in memory for longer (a write slowed to 100 MB/s: one frame
    // 112-115 MiB, three 143-146). What must not happen is growth from frame to frame.
    nonbloppy::ParticleSet tiled;
    tiled.positions = nonbloppy_bench::tiledFrame(kData + "/dam_break_frame_23_24389_particles.vtk", 2);
    fs::create_directories(dir() + "/in");
    for (const char* name : {"/in/fluid_1.ply", "/in/fluid_2.ply", "/in/fluid_3.ply", "/in/fluid_4.ply"}) {
        nonbloppy::writeParticles(tiled, dir() + name);
    }
    const RunResult r = run("mesh " + quote(in("fluid_{}.ply")) + " -o " + quote(out("mesh_{}.ply")) + " -q --log "
                            + quote(out("run.jsonl")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::vector<std::string> logLines = lines(readText(out("run.jsonl")));
    ASSERT_EQ(logLines.size(), 5u);
    ASSERT_NE(logLines[1].find("{\"frame\": 2, "), std::string::npos) << logLines[1];
    const double mebibyte = 1024.0 * 1024.0;
    const double second = numberAfter(logLines[1], "peak_rss_bytes") / mebibyte;
    const double all = numberAfter(logLines[4], "peak_rss_bytes") / mebibyte;
    ASSERT_GT(second, 0.0);
    ASSERT_GT(all, 0.0);  // -1: the log has no peak_rss_bytes
    EXPECT_LT(all, 1.1 * second) << "second frame done " << second << " MiB, all four " << all << " MiB";
    // That check passes without the hand-back at this size (the peaks stay within noise);
    // this one does not: once the last frame is written, nothing is in flight, and what its
    // stages freed must be back with the system, not kept in glibc's heap for a next frame.
    // Measured: 42-51 MiB at the end against peaks of 116-127 (0.36-0.40); with the
    // per-frame malloc_trim taken out, 74-81 MiB against 120-127 (0.61-0.65).
    const double end = numberAfter(logLines[4], "rss_bytes") / mebibyte;
    ASSERT_GT(end, 0.0) << logLines[4];  // -1: the summary has no rss_bytes
    EXPECT_LT(end, 0.5 * all) << "resident at the end " << end << " MiB, peak " << all << " MiB";
}

TEST_F(CliSequenceTest, MovingSpacingEstimateIsSaidOnceWithTheValuesThatPinTheLengths)
{
    // Frames 1 and 3 are the cube (s = 0.0498381), frame 2 the scattered particles (0.795085).
    makeFrames({kCube, kFree, kCube, kFree});
    const std::string mesh = "mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out("mesh_{}.obj")) + " -q";
    const std::string warning = "nonbloppy: warning: the spacing estimate moves between frames (0.0498381 in "
                                "frame 1, 0.795085 in frame 2) and the lengths derived from it move too; to "
                                "mesh every frame alike, give frame 1's:";
    RunResult r = run(mesh);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, warning + " --radius 0.0996763 --voxel-size 0.0249191 --threshold 2.85599 --max-step 0.0249191\n");

    // A length given is not listed; all three given, or the spacing, pin the frames alike.
    // (The radius has to suit frame 2's particles, 0.8 apart, and the voxel size both frames.)
    r = run(mesh + " --threshold 3 --frames 1-2");
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, warning + " --radius 0.0996763 --voxel-size 0.0249191 --max-step 0.0249191\n");
    for (const std::string& pinned : {std::string(" --spacing 0.3"),
                                      std::string(" --radius 1.6 --voxel-size 0.2 --threshold 3")}) {
        r = run(mesh + pinned + " --method paper --frames 1-2");
        ASSERT_EQ(r.exitCode, 0) << pinned << "\n" << r.err;
        EXPECT_EQ(r.err, "") << pinned;
    }

    // Frames alike: nothing to say. Two frame jobs: still said once.
    makeFrames({kCube, kCube, kCube, kCube});
    r = run(mesh);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err, "");
    // With two frame jobs the small frame 2 finishes first, and the warning named it as the
    // reference and pinned its lengths (hostile-input audit): now the same words as above.
    makeFrames({kCube, kFree, kCube, kFree});
    for (int repeat = 0; repeat < 3; ++repeat) {
        r = run(mesh + " --frame-jobs 2");
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_EQ(r.err, warning + " --radius 0.0996763 --voxel-size 0.0249191 --threshold 2.85599 --max-step 0.0249191\n");
    }
}

TEST_F(CliSequenceTest, TheLoggedLengthsAndStepCapGivenBackMeshTheSameBytes)
{
    // Strong relaxation, where the faithful step cap (s/2) shapes the surface. With r_e, r_0
    // and h all given and no spacing there is nothing to derive the cap from: pinning the
    // lengths alone changes the surface, so the warning above pins --max-step too.
    makeFrames({kData + "/dam_break_frame_23_24389_particles.vtk"});
    const std::string mesh = "mesh " + quote(in("fluid_{}.vtk")) + " -q -c 1 -t 4 -o ";
    RunResult r = run(mesh + quote(out("derived_{}.ply")) + " --log " + quote(out("derived.jsonl")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const std::string log = readText(out("derived.jsonl"));
    const auto given = [&](const char* option, const char* key) {
        char text[64];
        std::snprintf(text, sizeof(text), " %s %.17g", option, jsonNumber(log, key));
        return std::string(text);
    };
    ASSERT_GT(jsonNumber(log, "max_step"), 0.0) << log;
    const std::string derived = readText(out("derived_0001.ply"));
    ASSERT_GT(derived.size(), 100000u);
    const std::string lengths = given("--radius", "effective_radius") + given("--threshold", "threshold") +
                                given("--voxel-size", "voxel_size");
    r = run(mesh + quote(out("pinned_{}.ply")) + lengths + given("--max-step", "max_step"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(derived == readText(out("pinned_0001.ply")));

    r = run(mesh + quote(out("uncapped_{}.ply")) + lengths + " --log " + quote(out("uncapped.jsonl")));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(jsonNumber(readText(out("uncapped.jsonl")), "max_step"), 0.0);
    EXPECT_NE(readText(out("uncapped.jsonl")).find("\"spacing\": null"), std::string::npos);  // none derived
    EXPECT_FALSE(derived == readText(out("uncapped_0001.ply")));
    // The summary says which cap a run used.
    const std::string single = "mesh " + quote(in("fluid_0001.vtk")) + " -c 1 -t 4 -o " + quote(out("one.ply"));
    EXPECT_NE(run(single).out.find("  max step             0.0233607      (s/2)\n"), std::string::npos);
    EXPECT_NE(run(single + lengths).out.find("  max step             none           (no spacing to derive it from)\n"),
              std::string::npos);
    EXPECT_NE(run(single + " --max-step 0.01").out.find("  max step             0.01           (given)\n"),
              std::string::npos);
}

TEST_F(CliSequenceTest, RegionLeavesChangeOnlyTheVertexOrder)
{
    // --region-leaves 0 extracts the grid whole, 1 in regions of one leaf: the same
    // surface (plain method, no relaxation: the extracted mesh as it is), vertices in
    // another order. At h = 0.012 (half the default) the frame spans more than two regions'
    // least thickness (kMinLayersPerRegion leaf layers), so it is cut.
    const std::string dam = kData + "/bunny_frame_14_7705_particles.vtk";
    const std::string common = " --method paper -t 0 -q --quads --voxel-size 0.012";
    ASSERT_EQ(run("mesh " + quote(dam) + " -o " + quote(out("whole.obj")) + common + " --region-leaves 0").exitCode, 0);
    ASSERT_EQ(run("mesh " + quote(dam) + " -o " + quote(out("regions.obj")) + common + " --region-leaves 1").exitCode, 0);
    const auto sortedLines = [](const std::string& text, char kind) {
        std::vector<std::string> lines;
        std::istringstream in(text);
        for (std::string line; std::getline(in, line);) {
            if (line.size() > 1 && line[0] == kind && line[1] == ' ') lines.push_back(line);
        }
        std::sort(lines.begin(), lines.end());
        return lines;
    };
    const std::string whole = readText(out("whole.obj")), regions = readText(out("regions.obj"));
    EXPECT_NE(whole, regions);  // another order
    const std::vector<std::string> vertices = sortedLines(whole, 'v');
    ASSERT_GT(vertices.size(), 1000u);
    EXPECT_TRUE(vertices == sortedLines(regions, 'v'));
    // Each face as the positions of its corners, from the smallest on (the winding kept):
    // the same polygons whatever the vertex numbering.
    const auto facesByPosition = [](const std::string& text) {
        std::vector<std::string> positions, faces;
        std::istringstream in(text);
        for (std::string line; std::getline(in, line);) {
            if (line.rfind("v ", 0) == 0) positions.push_back(line.substr(2));
            if (line.rfind("f ", 0) != 0) continue;
            std::vector<std::string> corners;
            std::istringstream face(line.substr(2));
            for (std::string corner; face >> corner;) {
                corners.push_back(positions.at(std::stoul(corner.substr(0, corner.find('/'))) - 1));
            }
            std::rotate(corners.begin(), std::min_element(corners.begin(), corners.end()), corners.end());
            std::string joined;
            for (const std::string& c : corners) joined += c + "|";
            faces.push_back(joined);
        }
        std::sort(faces.begin(), faces.end());
        return faces;
    };
    const std::vector<std::string> faces = facesByPosition(whole);
    ASSERT_GT(faces.size(), 1000u);
    EXPECT_TRUE(faces == facesByPosition(regions));
}

TEST_F(CliSequenceTest, MeshWithoutVdbIsTheSameMesh)
{
    // Without --vdb the tool lets the library drop the grid early (less memory); the mesh
    // must not change by a bit.
    const std::string dam = kData + "/bunny_frame_14_7705_particles.vtk";
    const RunResult without = run("mesh " + quote(dam) + " -o " + quote(out("a.obj")));
    ASSERT_EQ(without.exitCode, 0) << without.err;
    EXPECT_NE(without.out.find("(density grid not kept without --vdb)"), std::string::npos)
        << without.out;
    ASSERT_EQ(run("mesh " + quote(dam) + " -o " + quote(out("b.obj")) + " --vdb "
                  + quote(out("b.vdb")) + " -q").exitCode, 0);
    EXPECT_TRUE(readText(out("a.obj")) == readText(out("b.obj"))) << "meshes differ";
}

TEST_F(CliSequenceTest, AWarningEveryFrameWouldGiveIsGivenOncePerRun)
{
    // c = 0.5, t = 4 relax too strongly for the calibrated threshold (test_cli.cc): every
    // frame would warn; the run says it once, with one frame job or two.
    makeFrames({kCube, kCube, kCube});
    const std::string warning = "nonbloppy: warning: --blend 0.5 --iterations 4 relax too strongly for --threshold "
                                "to be calibrated: flat faces end inside the particles; lower --blend or "
                                "--iterations, or give --spacing to correct the volume\n";
    for (const char* jobs : {"1", "2"}) {
        const RunResult r = run("mesh " + quote(in("fluid_{}.vtk")) + " -o " + quote(out(std::string("jobs") + jobs + "_{}.ply"))
                                + " -q --blend 0.5 --iterations 4 --frame-jobs " + jobs);
        ASSERT_EQ(r.exitCode, 0) << r.err;
        EXPECT_EQ(r.err, warning) << jobs << " frame jobs";
    }
}
