// SPDX-License-Identifier: Apache-2.0
#include "TestUtil.h"

#include <nonbloppy/Error.h>
#include <nonbloppy/ReadVdb.h>
#include <nonbloppy/Version.h>
#include <nonbloppy/WriteVdb.h>

#include <gtest/gtest.h>

#include <openvdb/tools/LevelSetSphere.h>

using nonbloppy::FileError;
using nonbloppy::readVdbFile;

namespace {

class ReadVdbTest : public nonbloppy_test::ScratchDirTest
{
protected:
    /// A fog volume of 8 leaves and a level-set sphere of about 100 leaves: its delayed-load
    /// arrays (a byte and 8 bytes per leaf) are the sizes OpenVDB pads before compressing.
    std::string writeTwoGrids()
    {
        openvdb::initialize();
        openvdb::FloatGrid::Ptr density = openvdb::FloatGrid::create(0.0f);
        density->setName("density");
        density->setGridClass(openvdb::GRID_FOG_VOLUME);
        for (int i = 0; i < 8; ++i) density->tree().setValue(openvdb::Coord(8 * i, 0, 0), float(i + 1));
        openvdb::FloatGrid::Ptr sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(3.0f, openvdb::Vec3f(0.0f), 0.2f);
        sphere->setName("surface");
        openvdb::MetaMap metadata;
        metadata.insertMeta("creator", openvdb::StringMetadata("test"));
        const std::string file = path("grids.vdb");
        nonbloppy::writeVdb({density, sphere}, file, metadata);
        mSphereLeaves = sphere->tree().leafCount();
        mSphereVoxels = sphere->activeVoxelCount();
        return file;
    }
    openvdb::Index64 mSphereLeaves = 0, mSphereVoxels = 0;
};

} // namespace

TEST_F(ReadVdbTest, ReadsBackEveryGridAndTheFileMetadata)
{
    const std::string file = writeTwoGrids();
    EXPECT_GT(mSphereLeaves, 48u);   // compressed, and
    EXPECT_LT(mSphereLeaves, 128u);  // padded to 128 bytes by OpenVDB
    const nonbloppy::VdbFileContents contents = readVdbFile(file);
    ASSERT_EQ(contents.grids.size(), 2u);
    EXPECT_EQ(contents.grids[0]->getName(), "density");
    EXPECT_EQ(contents.grids[0]->activeVoxelCount(), 8u);
    EXPECT_EQ(contents.grids[1]->getName(), "surface");
    EXPECT_EQ(contents.grids[1]->activeVoxelCount(), mSphereVoxels);
    EXPECT_EQ(contents.metadata.metaValue<std::string>("creator"), "test");
    EXPECT_EQ(contents.formatVersion, std::to_string(openvdb::OPENVDB_LIBRARY_MAJOR_VERSION) + "."
                                          + std::to_string(openvdb::OPENVDB_LIBRARY_MINOR_VERSION) + "/"
                                          + std::to_string(openvdb::OPENVDB_FILE_VERSION));
}

TEST_F(ReadVdbTest, AFileWrittenWithoutACreatorNamesNonbloppyAndOpenVdbWithTheirVersions)
{
    openvdb::initialize();
    openvdb::FloatGrid::Ptr density = openvdb::FloatGrid::create(0.0f);
    density->tree().setValue(openvdb::Coord(1, 2, 3), 1.0f);
    const std::string file = path("plain.vdb");
    nonbloppy::writeVdb({density}, file);
    EXPECT_EQ(readVdbFile(file).metadata.metaValue<std::string>("creator"), nonbloppy::versionLine());
    EXPECT_EQ(nonbloppy::versionLine(), std::string("nonbloppy ") + nonbloppy::version() + " (OpenVDB "
                                            + openvdb::getLibraryVersionString() + ")");
}

TEST_F(ReadVdbTest, GridsSharingATreeReadBack)
{
    // A grid copied with copy() shares its tree; the file stores the tree once and the copy
    // as an instance with block offset 0, which the layout check refused as corrupt (bug hunt).
    openvdb::initialize();
    openvdb::FloatGrid::Ptr a = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(1.0f, openvdb::Vec3f(0.0f), 0.1f);
    a->setName("a");
    openvdb::FloatGrid::Ptr b = a->copy();
    b->setName("b");
    const std::string file = path("shared.vdb");
    nonbloppy::writeVdb({a, b}, file);
    const nonbloppy::VdbFileContents contents = readVdbFile(file);
    ASSERT_EQ(contents.grids.size(), 2u);
    EXPECT_EQ(contents.grids[1]->getName(), "b");
    EXPECT_EQ(contents.grids[1]->activeVoxelCount(), a->activeVoxelCount());
    EXPECT_GT(a->activeVoxelCount(), 1000u);
}

TEST_F(ReadVdbTest, EveryTruncationIsAOneLineErrorNamingTheFile)
{
    // io::File read these with gigabyte allocations and messages of a billion spaces, or
    // returned "0 grids" for a file cut in its header.
    const std::string bytes = nonbloppy_test::readBytes(writeTwoGrids());
    const std::string cut = path("cut.vdb");
    for (size_t k = 0; k < bytes.size(); k += (k < 256 ? 1 : 37)) {
        nonbloppy_test::writeBytes(cut, bytes.substr(0, k));
        const std::string message = nonbloppy_test::messageOf<FileError>([&] { readVdbFile(cut); });
        ASSERT_FALSE(message.empty()) << "cut at " << k << " of " << bytes.size() << " was read";
        EXPECT_EQ(message.rfind("cannot read .vdb file: ", 0), 0u) << message;
        EXPECT_NE(message.find("(" + cut + ")"), std::string::npos) << message;
        EXPECT_LT(message.size(), 400u);
        EXPECT_EQ(message.find('\n'), std::string::npos);
    }
    nonbloppy_test::writeBytes(cut, bytes.substr(0, 4));
    EXPECT_EQ(nonbloppy_test::messageOf<FileError>([&] { readVdbFile(cut); }),
              "cannot read .vdb file: not a VDB file (" + cut + ")");
}

TEST_F(ReadVdbTest, GridAndBlockOffsetsMustLieInTheirGrid)
{
    // One byte changed in a grid's offset made io::File read past the end of the file into
    // uninitialised string lengths: some runs allocated 4-10 GB for a minute (valgrind:
    // reads of uninitialised values in Transform::read).
    const std::string bytes = nonbloppy_test::readBytes(writeTwoGrids());
    // The second grid's descriptor ends with its grid, block and end offsets; the end is
    // the file's size.
    const int64_t fileSize = int64_t(bytes.size());
    size_t endAt = std::string::npos;
    for (size_t k = 0; k + 8 <= bytes.size(); ++k) {
        if (std::memcmp(bytes.data() + k, &fileSize, 8) == 0) endAt = k;
    }
    ASSERT_NE(endAt, std::string::npos);
    ASSERT_GE(endAt, 16u);
    const std::string bad = path("bad.vdb");
    for (const size_t at : {endAt - 16 + 7, endAt - 8 + 7, endAt - 16}) {
        std::string changed = bytes;
        changed[at] = char(changed[at] ^ 0x35);
        nonbloppy_test::writeBytes(bad, changed);
        const std::string message = nonbloppy_test::messageOf<FileError>([&] { readVdbFile(bad); });
        EXPECT_EQ(message.rfind("cannot read .vdb file: corrupt grid 'surface' (its grid and block offsets ", 0), 0u)
            << message;
        EXPECT_NE(message.find("(" + bad + ")"), std::string::npos) << message;
    }
}
