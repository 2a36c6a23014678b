// SPDX-License-Identifier: Apache-2.0
// Inputs the fuzz targets (tests/fuzz/) found, and hostile headers made by hand, kept in
// tests/data/fuzz/: each must give its exact one-line FileError, never a crash. Every file
// there needs an entry in kExpected below (FuzzRegressions.EveryFileHasAnEntry checks it).
//
// The header bombs (billion_points_header.*) claim a billion points in about 1 KB; the
// reader must reject them before allocating for those points: the largest single request
// made while a file is read is recorded (support/AllocationRecorder.h).

#include "TestUtil.h"
#include "support/AllocationRecorder.h"
#include "support/OpenVdbPoints.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>
#include <nonbloppy/ReadVdb.h>

#include <openvdb/openvdb.h>

#include <gtest/gtest.h>

#include <dirent.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace {

std::string
fuzzPath(const std::string& name)
{
    return std::string(NONBLOPPY_TEST_DATA_DIR) + "/fuzz/" + name;
}

struct ReadOutcome
{
    std::string message;          ///< the FileError's text, or why there was none
    size_t largestAllocation = 0; ///< largest single operator new request while reading
};

ReadOutcome
readFuzzFile(const std::string& path)
{
    ReadOutcome outcome;
    outcome.largestAllocation = nonbloppy_test::largestAllocationDuring([&] {
        try {
            nonbloppy::readParticles(path);
            outcome.message = "(no FileError)";
        } catch (const nonbloppy::FileError& e) {
            outcome.message = e.what();
        } catch (const std::exception& e) {
            outcome.message = std::string("(other exception) ") + e.what();
        }
    });
    return outcome;
}

/// Each file in tests/data/fuzz/ and the message its reader must give, without the
/// " (<path>)" every FileError ends with.
struct Expected
{
    const char* file;
    const char* message;
};

const Expected kExpected[] = {
    // fuzz_vdb_points: a stream OpenVDB rejected halfway through a grid's tree, leaking a
    // node (upstream, once suppressed in tests/fuzz/lsan.supp): a Blosc chunk of an internal
    // node whose own header says 0 bytes. The check of Blosc headers in the tree now rejects
    // it first.
    {"vdb_points_corrupt_stream_openvdb_leak.vdb",
     "cannot read .vdb file: Blosc chunk in tree of grid 'points' says 0 bytes from 16 in blocks "
     "of 1; expected 8 bytes from 16"},
    // fuzz_vdb_points: two bytes changed inside the Blosc data of the P attribute's page.
    // Every size is right; OpenVDB's Blosc decompression failed and threw, leaking the page
    // and its handles (856 bytes in 16 objects under LeakSanitizer). The walk now
    // decompresses every Blosc chunk of the leaf buffers first.
    {"vdb_points_corrupt_blosc_data_openvdb_error.vdb",
     "cannot read .vdb file: corrupt Blosc chunk in page of attribute 0 of leaf 0 of grid "
     "'points': it does not decompress to the 128 bytes its header gives"},
    // Hand-made: 8 points written by io::File with COMPRESS_BLOSC, then COMPRESS_ZIP, alone
    // (no active mask, so the root child's 32^3 tile values are a 131072-byte chunk), one
    // byte of that chunk's compressed data set to 0xff. Every size is right; OpenVDB threw
    // in RootNode::readTopology and leaked the 270 352-byte node. The walk now decompresses
    // every chunk of the topology first.
    {"vdb_points_tree_corrupt_blosc_data_openvdb_leak.vdb",
     "cannot read .vdb file: corrupt Blosc chunk in tree of grid 'points': it does not "
     "decompress to the 131072 bytes its header gives"},
    {"vdb_points_tree_corrupt_zlib_data_openvdb_leak.vdb",
     "cannot read .vdb file: corrupt zlib chunk in tree of grid 'points' (data error)"},
    // A grid metadata type name claiming 2 GB: libopenvdb allocated it before failing, until
    // the reader checked every string length against the bytes left (VdbSizeCheck).
    {"vdb_points_metadata_type_name_2gb.vdb",
     "cannot read .vdb file: type name of metadata 'file_voxel_count' of grid 'points' claims "
     "2147483653 bytes, 10238 left"},
    // fuzz_vdb_points, first run: a file cut short inside the tree. OpenVDB does not check its
    // reads, so it took a Blosc chunk size from uninitialised memory and asked for ~140 TB.
    // The stream now throws on a short read, and the tree's topology is walked first.
    {"vdb_points_truncated_tree_uninitialised_blosc_size.vdb",
     "cannot read .vdb file: tree of grid 'points' claims 1 root children in 6117 bytes"},
    // fuzz_vdb_points, later runs: a node's value chunk in the tree claims more than the file
    // holds; io::bloscFromStream allocated it before reading. Caught by the topology walk.
    {"vdb_points_tree_chunk_size_286tb.vdb",
     "cannot read .vdb file: compressed chunk in tree of grid 'points' claims 285886696653058 "
     "bytes, 288 left"},
    {"vdb_points_tree_chunk_size_345gb.vdb",
     "cannot read .vdb file: compressed chunk in tree of grid 'points' claims 345073778944 "
     "bytes, 2 left"},
    {"vdb_points_tree_chunk_size_2pb.vdb",
     "cannot read .vdb file: compressed chunk in tree of grid 'points' claims 1695446930030592 "
     "bytes, 381 left"},
    {"vdb_points_tree_chunk_size_11pb.vdb",
     "cannot read .vdb file: compressed chunk in tree of grid 'points' claims 10901657789399040 "
     "bytes, 1548 left"},
    {"vdb_points_tree_chunk_size_1eb.vdb",
     "cannot read .vdb file: compressed chunk in tree of grid 'points' claims 1224986145949244008 "
     "bytes, 129 left"},
    {"vdb_points_tree_chunk_size_7eb.vdb",
     "cannot read .vdb file: compressed chunk in tree of grid 'points' claims 7349874591868649472 "
     "bytes, 494 left"},
    // fuzz_vdb_points, 300 s runs: the first leaf's attribute descriptor claims billions of
    // attributes; AttributeSet::Descriptor::read sized a vector by it (up to 1.2 TB). Its
    // header byte, which OpenVDB checks only after reading the descriptor, is rejected first.
    {"vdb_points_leaf_descriptor_attribute_count_1tb.vdb",
     "cannot read .vdb file: unknown header flags 111 in leaf 0 of grid 'points'"},
    {"vdb_points_leaf_descriptor_attribute_count_563t.vdb",
     "cannot read .vdb file: unknown header flags 99 in leaf 0 of grid 'points'"},
    // fuzz_vdb_points, 120 s run: a non-zero root background; leaves are made with it and
    // PointDataLeafNode asserts it is 0, so Debian's libopenvdb (built with assertions) aborted.
    {"vdb_points_tree_nonzero_background_assert.vdb",
     "cannot read .vdb file: tree of grid 'points' has background 3735552; point grids need 0"},
    // fuzz_vdb_points, runs 8-12 (tests/fuzz/README.md), in the leaf buffers past the first
    // descriptor, which libopenvdb read unchecked until the walk covered every leaf. A zero
    // page size or an array running past its page failed an assert in libopenvdb's
    // compression::Page::readHeader / PagedInputStream, and Debian's libopenvdb keeps
    // assertions, so the process aborted; the fourth leaf's own descriptor asked for 5 PB.
    // Each is now rejected by the first check its bytes fail.
    {"vdb_points_array_size_zero_page_size_zero_assert.vdb",
     "cannot read .vdb file: attribute 'velocity' of leaf 0 of grid 'points' has size 0 and stride 1"},
    {"vdb_points_page_uncompressed_size_zero_assert.vdb",
     "cannot read .vdb file: page header of attribute 0 of leaf 0 of grid 'points' gives "
     "uncompressed size 0"},
    {"vdb_points_array_byte_count_16mb_page_overrun_assert.vdb",
     "cannot read .vdb file: attribute 'velocity' of leaf 0 of grid 'points' claims 16253120 "
     "bytes, expected 192 for 8 values of 24 bytes"},
    {"vdb_points_leaf3_header_flags_descriptor_alloc_5pb.vdb",
     "cannot read .vdb file: unknown header flags 31 in leaf 3 of grid 'points'"},
    // Hand-made from tests/fuzz/seeds/cube_8_points.vdb (one field of the P attribute's page
    // changed), one per check of the page walk: the compressed size of its page header 0
    // (the assert above), its uncompressed size 48 for a 96-byte array (PagedInputStream's
    // assert) or 200 (the data pass would never load the page, and the array would be
    // copied from a page with no buffer), and the compressed size in the Blosc chunk's own
    // header 4000 for a 58-byte chunk (Blosc would read past it).
    {"vdb_points_page_compressed_size_zero_assert.vdb",
     "cannot read .vdb file: page header of attribute 0 of leaf 0 of grid 'points' gives "
     "compressed size 0"},
    {"vdb_points_array_past_page_end_assert.vdb",
     "cannot read .vdb file: array of 96 bytes in attribute 0 of leaf 0 of grid 'points' runs "
     "past its page (48 bytes left in it)"},
    {"vdb_points_page_longer_than_its_arrays.vdb",
     "cannot read .vdb file: last page of attribute 0 in leaf buffers of grid 'points' holds "
     "200 bytes, its arrays 96"},
    {"vdb_points_blosc_header_compressed_size_4000.vdb",
     "cannot read .vdb file: Blosc chunk in page of attribute 0 of leaf 0 of grid 'points' says "
     "128 bytes from 4000 in blocks of 128; expected 96 bytes from 58"},
    // A billion points claimed in about 1 KB, one file per reader that reads a count
    // (.vdb: the P attribute array of the only leaf says 1e9 values; its byte count, 96).
    {"billion_points_header.bgeo",
     "truncated BGEO points: header claims 1000000000 points of 16 bytes, 983 bytes left"},
    {"billion_points_header.vtu", "truncated Points: the file is too small for 1000000000 tuples"},
    {"billion_points_header.vtk", "truncated POINTS section"},
    {"billion_points_header.ply", "truncated PLY vertex element"},
    {"billion_points_header.vdb",
     "cannot read .vdb file: attribute 'P' of leaf 0 of grid 'points' claims 96 bytes, expected "
     "12000000000 for 1000000000 values of 12 bytes"},
};

const Expected*
expectedFor(const std::string& file)
{
    for (const Expected& entry : kExpected) {
        if (file == entry.file) return &entry;
    }
    return nullptr;
}

std::vector<std::string>
fuzzFiles()
{
    std::vector<std::string> files;
    if (DIR* dir = opendir(fuzzPath("").c_str())) {
        while (const dirent* entry = readdir(dir)) {
            const std::string name = entry->d_name;
            if (name[0] != '.' && name.find('.') != std::string::npos) files.push_back(name);
        }
        closedir(dir);
    }
    std::sort(files.begin(), files.end());
    return files;
}

void
expectMessage(const std::string& file)
{
    const Expected* expected = expectedFor(file);
    ASSERT_NE(expected, nullptr) << file << " has no entry in kExpected";
    const std::string path = fuzzPath(file);
    const ReadOutcome outcome = readFuzzFile(path);
    EXPECT_EQ(outcome.message, std::string(expected->message) + " (" + path + ")") << file;
}

TEST(FuzzRegressions, TheAllocationRecorderSeesRequestsOfThisThreadOnly)
{
    // Every "refused before allocating" check rests on this: a large request is seen, one of
    // another thread is not, and nothing is recorded outside the work.
    const size_t mine = nonbloppy_test::largestAllocationDuring([] {
        std::vector<char> block(size_t(5) << 20);
        EXPECT_EQ(block.size(), size_t(5) << 20);
    });
    EXPECT_GE(mine, size_t(5) << 20);
    const size_t other = nonbloppy_test::largestAllocationDuring([] {
        std::thread([] { std::vector<char> block(size_t(5) << 20); }).join();
    });
    EXPECT_LT(other, size_t(1) << 20);
    std::vector<char> outside(size_t(6) << 20);
    EXPECT_LT(nonbloppy_test::largestAllocationDuring([] {}), size_t(1) << 20);
}

TEST(FuzzRegressions, EveryFileHasAnEntry)
{
    const std::vector<std::string> files = fuzzFiles();
    EXPECT_FALSE(files.empty());
    for (const std::string& file : files) {
        EXPECT_NE(expectedFor(file), nullptr) << "tests/data/fuzz/" << file
            << " has no entry in kExpected (tests/test_FuzzRegressions.cc)";
    }
    for (const Expected& entry : kExpected) {
        EXPECT_NE(std::find(files.begin(), files.end(), entry.file), files.end())
            << entry.file << " is missing from tests/data/fuzz/";
    }
}

TEST(FuzzRegressions, EveryFileGivesItsExactError)
{
    for (const std::string& file : fuzzFiles()) expectMessage(file);
}

// fuzz_vdb_points: corrupt compressed data behind right sizes is rejected before OpenVDB
// reads the tree, so it never builds (and leaks) a node: the largest request while reading
// stays below a level-2 internal node (270 352 bytes; the walk decompresses into a buffer of
// at most 131 088 bytes here).
TEST(FuzzRegressions, VdbCorruptStream)
{
    for (const char* file : {"vdb_points_corrupt_blosc_data_openvdb_error.vdb",
                             "vdb_points_tree_corrupt_blosc_data_openvdb_leak.vdb",
                             "vdb_points_tree_corrupt_zlib_data_openvdb_leak.vdb"}) {
        expectMessage(file);
        const ReadOutcome outcome = readFuzzFile(fuzzPath(file));
        EXPECT_LT(outcome.largestAllocation, size_t(270352)) << file;
    }
}

// "A file that claims a billion points in a 1 KB file is rejected before any allocation":
// nothing sized by the claimed count is requested. A billion points would be 12 GB; the
// largest fixed-size request on these paths is an OpenVDB tree node (270 KB).
TEST(FuzzRegressions, BillionPointHeadersAreRejectedBeforeAllocating)
{
    for (const char* file : {"billion_points_header.bgeo", "billion_points_header.vtu",
                             "billion_points_header.vtk", "billion_points_header.ply",
                             "billion_points_header.vdb"}) {
        expectMessage(file);
        const ReadOutcome outcome = readFuzzFile(fuzzPath(file));
        EXPECT_LT(outcome.largestAllocation, size_t(1) << 20) << file;
    }
}

// The inputs that aborted the process inside libopenvdb (or made it ask for petabytes) are
// rejected before libopenvdb reads the leaf buffers: nothing of 1 MB or more is requested.
TEST(FuzzRegressions, VdbLeafBuffersAreCheckedBeforeOpenVdbReadsThem)
{
    for (const char* file : {"vdb_points_array_size_zero_page_size_zero_assert.vdb",
                             "vdb_points_page_uncompressed_size_zero_assert.vdb",
                             "vdb_points_array_byte_count_16mb_page_overrun_assert.vdb",
                             "vdb_points_leaf3_header_flags_descriptor_alloc_5pb.vdb",
                             "vdb_points_page_compressed_size_zero_assert.vdb",
                             "vdb_points_array_past_page_end_assert.vdb",
                             "vdb_points_page_longer_than_its_arrays.vdb",
                             "vdb_points_blosc_header_compressed_size_4000.vdb"}) {
        expectMessage(file);
        const ReadOutcome outcome = readFuzzFile(fuzzPath(file));
        EXPECT_LT(outcome.largestAllocation, size_t(1) << 20) << file;
    }
}

// The leaf-buffer walk of src/ReadVdbPoints.cc checks every page and array size against
// what OpenVDB writes; it must not reject what OpenVDB writes. Point grids with each of
// io::File's compressions (Blosc: paged arrays; zip and none: arrays read whole), several
// pages per attribute (2.4 MB of positions, 1 MB pages), arrays shorter than Blosc's padding,
// a leaf whose array is larger than a page, uniform, strided and group attributes.
class VdbLeafBuffers : public nonbloppy_test::ScratchDirTest
{
protected:
    /// @a count points in a cube of side @a extent (voxel size 1), with a float
    /// "temperature" (the point's number / 2), a uniform int "id", a non-uniform float
    /// pair "pair" (stride 2) and a group "tagged".
    std::string writePoints(size_t count, double extent, uint32_t compression, const std::string& name)
    {
        std::mt19937 random(11);
        std::uniform_real_distribution<double> coordinate(0.0, extent);
        std::vector<openvdb::Vec3R> positions(count);
        for (openvdb::Vec3R& p : positions) p = openvdb::Vec3R(coordinate(random), coordinate(random), coordinate(random));
        const std::string file = path(name);
        nonbloppy_test::writeOpenVdbPoints(file, positions, 1.0, nonbloppy_test::PointExtras::IdPairAndGroup,
                                           compression);
        return file;
    }

    static void expectPoints(const std::string& file, size_t count)
    {
        const nonbloppy::ParticleSet particles = nonbloppy::readParticles(file);
        ASSERT_EQ(particles.size(), count) << file;
        const nonbloppy::ParticleAttribute& t = nonbloppy_test::attribute(particles, "temperature");
        std::vector<double> values(count);
        for (size_t n = 0; n < count; ++n) values[n] = t.asDouble(n);
        std::sort(values.begin(), values.end());
        for (size_t n = 0; n < count; ++n) ASSERT_EQ(values[n], double(float(n) * 0.5f)) << file;
    }
};

TEST_F(VdbLeafBuffers, WhatOpenVdbWritesStillReads)
{
    using namespace openvdb::io;
    for (const uint32_t compression : {uint32_t(COMPRESS_BLOSC | COMPRESS_ACTIVE_MASK),
                                       uint32_t(COMPRESS_ZIP | COMPRESS_ACTIVE_MASK), uint32_t(COMPRESS_NONE)}) {
        const std::string tag = std::to_string(compression);
        // 200 000 points in 40³ voxels: ~600 leaves, positions over three pages.
        expectPoints(writePoints(200000, 40.0, compression, "many_leaves_" + tag + ".vdb"), 200000);
        // 8 points in one leaf: arrays shorter than Blosc's 128-byte padding.
        expectPoints(writePoints(8, 2.0, compression, "eight_points_" + tag + ".vdb"), 8);
        // 100 000 points in one voxel: one leaf whose arrays exceed a page.
        expectPoints(writePoints(100000, 0.9, compression, "one_leaf_" + tag + ".vdb"), 100000);
    }
}

} // namespace

// readVdbFile() ('nonbloppy inspect') walks every PointDataGrid's leaves as readParticles()
// does before OpenVDB reads them: it read them unchecked, and OpenVDB's assertions on page
// sizes aborted the process (exit 134) on five of these files. Same message, word for word,
// except where its layout walk finds first that the grid ends beyond the file.
TEST(FuzzRegressions, ReadVdbFileRefusesEveryVdbFileAsReadParticlesDoes)
{
    size_t vdbFiles = 0, truncated = 0;
    for (const std::string& file : fuzzFiles()) {
        if (file.size() < 4 || file.compare(file.size() - 4, 4, ".vdb") != 0) continue;
        ++vdbFiles;
        const std::string path = fuzzPath(file);
        std::string message = "(no FileError)";
        try {
            nonbloppy::readVdbFile(path);
        } catch (const nonbloppy::FileError& e) {
            message = e.what();
        }
        if (message.rfind("cannot read .vdb file: truncated grid 'points' (it ends at byte ", 0) == 0) {
            ++truncated;
            continue;
        }
        EXPECT_EQ(message, readFuzzFile(path).message) << file;
    }
    EXPECT_GE(vdbFiles, size_t(20));
    EXPECT_LE(truncated, vdbFiles / 2);
}
