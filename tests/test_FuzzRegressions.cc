// SPDX-License-Identifier: Apache-2.0
// Inputs the fuzz targets (tests/fuzz/) found, and hostile headers made by hand, kept in
// tests/data/fuzz/: each must give its exact one-line FileError, never a crash. Every file
// there needs an entry in kExpected below (FuzzRegressions.EveryFileHasAnEntry checks it).
//
// The header bombs (billion_points_header.*) claim a billion points in about 1 KB; the
// reader must reject them before allocating for those points. This file replaces the global
// operator new to record the largest single request made while a file is being read.

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadParticles.h>

#include <gtest/gtest.h>

#include <dirent.h>

#include <algorithm>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

namespace {

// Recording happens on the reading thread only, and only while it is armed.
thread_local bool tRecordAllocations = false;
thread_local size_t tLargestAllocation = 0;

void*
recordedAllocation(std::size_t size) noexcept
{
    if (tRecordAllocations && size > tLargestAllocation) tLargestAllocation = size;
    return std::malloc(size == 0 ? 1 : size);
}

} // namespace

// Every non-aligned form is replaced, so all of them pair malloc with free (AddressSanitizer
// checks that allocation and deallocation functions match); aligned forms stay the library's.
void*
operator new(std::size_t size)
{
    if (void* p = recordedAllocation(size)) return p;
    throw std::bad_alloc();
}

void*
operator new[](std::size_t size)
{
    if (void* p = recordedAllocation(size)) return p;
    throw std::bad_alloc();
}

void* operator new(std::size_t size, const std::nothrow_t&) noexcept { return recordedAllocation(size); }
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept { return recordedAllocation(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }

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
    tLargestAllocation = 0;
    tRecordAllocations = true;
    try {
        nonbloppy::readParticles(path);
        outcome.message = "(no FileError)";
    } catch (const nonbloppy::FileError& e) {
        outcome.message = e.what();
    } catch (const std::exception& e) {
        outcome.message = std::string("(other exception) ") + e.what();
    }
    tRecordAllocations = false;
    outcome.largestAllocation = tLargestAllocation;
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
    // fuzz_vdb_points: a stream OpenVDB rejects halfway through a grid (libopenvdb leaks a
    // node on that path, upstream; see tests/fuzz/lsan.supp).
    {"vdb_points_corrupt_stream_openvdb_leak.vdb",
     "cannot read .vdb file: RuntimeError: Expected to decompress 8 bytes, got 0 bytes"},
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
    // attributes; AttributeSet::Descriptor::read sized a vector by it (up to 1.2 TB).
    {"vdb_points_leaf_descriptor_attribute_count_1tb.vdb",
     "cannot read .vdb file: attribute descriptor in leaf buffers of grid 'points' claims "
     "18881471093 attributes"},
    {"vdb_points_leaf_descriptor_attribute_count_563t.vdb",
     "cannot read .vdb file: attribute descriptor in leaf buffers of grid 'points' claims "
     "562949954234675 attributes"},
    // fuzz_vdb_points, 120 s run: a non-zero root background; leaves are made with it and
    // PointDataLeafNode asserts it is 0, so Debian's libopenvdb (built with assertions) aborted.
    {"vdb_points_tree_nonzero_background_assert.vdb",
     "cannot read .vdb file: tree of grid 'points' has background 3735552; point grids need 0"},
    // A billion points claimed in about 1 KB, one file per reader that reads a count
    // (.vdb: the P attribute array of the only leaf says 1e9 values; the leaf holds 8).
    {"billion_points_header.bgeo",
     "truncated BGEO points: header claims 1000000000 points of 16 bytes, 983 bytes left"},
    {"billion_points_header.vtu", "truncated Points: the file is too small for 1000000000 tuples"},
    {"billion_points_header.vtk", "truncated POINTS section"},
    {"billion_points_header.ply", "truncated PLY vertex element"},
    {"billion_points_header.vdb", "corrupt attribute array in PointDataGrid 'points'"},
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

// fuzz_vdb_points: the reader turns OpenVDB's exception into a FileError naming the file.
TEST(FuzzRegressions, VdbCorruptStream)
{
    expectMessage("vdb_points_corrupt_stream_openvdb_leak.vdb");
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

} // namespace
