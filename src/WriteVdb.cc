// SPDX-License-Identifier: Apache-2.0
/// @file WriteVdb.cc
/// @brief Stage "write vdb": the grids as io::File writes them, into a temporary file through
///        a stream whose errors are checked, a deterministic file UUID patched into its
///        header, then a rename into place (AtomicFile).

#include <nonbloppy/WriteVdb.h>

#include <nonbloppy/Error.h>
#include <nonbloppy/Version.h>

#include "AtomicFile.h"

#include <openvdb/io/Archive.h>

#include <array>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

namespace nonbloppy {

namespace write_vdb_internal {

/// io::File::write() as it is (io::Archive::write() to a std::ofstream, seekable), but onto
/// a stream the caller owns: io::File never checks its stream, so a full disk gave a
/// truncated .vdb and no error.
class StreamArchive : public openvdb::io::Archive
{
public:
    void writeSeekable(std::ostream& os, const openvdb::GridCPtrVec& grids, const openvdb::MetaMap& metadata) const
    {
        openvdb::io::Archive::write(os, grids, /*seekable=*/true, metadata);
    }
};

/// Layout of the VDB file header as io::Archive::writeHeader() writes it (file format ≥ 220):
/// int64 magic, uint32 file version, uint32 library major, uint32 library minor,
/// char "has grid offsets", then the file UUID as 36 ASCII characters.
constexpr std::streamoff kUuidOffset = 8 + 4 + 4 + 4 + 1;
constexpr size_t kUuidLength = 36;
constexpr int64_t kVdbMagic = 0x56444220; // " BDV"

/// io::File writes a random UUID into every file, so two writes of the same grids would
/// differ. Replacing it by a hash of the rest of the file keeps the UUID's purpose
/// (different contents, different UUIDs) and makes the bytes reproducible.
/// Two FNV-1a 64-bit hashes with different offset bases give the 128 bits.
class ContentHash
{
public:
    void update(const char* data, size_t size)
    {
        for (size_t i = 0; i < size; ++i) {
            const uint64_t byte = static_cast<unsigned char>(data[i]);
            mA = (mA ^ byte) * kPrime;
            mB = (mB ^ ((byte + 0x5bu) & 0xffu)) * kPrime;
        }
    }

    /// The hash as a UUID string "xxxxxxxx-xxxx-8xxx-[89ab]xxx-xxxxxxxxxxxx" (RFC 9562
    /// version 8, "custom"), which boost::uuids::string_generator parses when reading.
    std::string uuid() const
    {
        std::array<unsigned char, 16> bytes;
        for (int i = 0; i < 8; ++i) {
            bytes[i] = static_cast<unsigned char>(mA >> (8 * i));
            bytes[8 + i] = static_cast<unsigned char>(mB >> (8 * i));
        }
        bytes[6] = static_cast<unsigned char>((bytes[6] & 0x0f) | 0x80); // version 8
        bytes[8] = static_cast<unsigned char>((bytes[8] & 0x3f) | 0x80); // RFC variant
        static const char* hex = "0123456789abcdef";
        std::string s;
        for (int i = 0; i < 16; ++i) {
            if (i == 4 || i == 6 || i == 8 || i == 10) s += '-';
            s += hex[bytes[i] >> 4];
            s += hex[bytes[i] & 0xf];
        }
        return s;
    }

private:
    static constexpr uint64_t kPrime = 0x100000001b3ull;
    uint64_t mA = 0xcbf29ce484222325ull;
    uint64_t mB = 0x84222325cbf29ce4ull;
};

/// Overwrite the UUID of the VDB file at @a path with a hash of its other bytes.
/// @throw FileError (naming @a finalPath) if the file is not laid out as expected.
void makeUuidDeterministic(const std::string& path, const std::string& finalPath)
{
    std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
    if (!file) {
        throw FileError("cannot write " + finalPath + ": cannot reopen temporary file "
                        + path + " (" + std::strerror(errno) + ")");
    }
    char header[kUuidOffset + kUuidLength];
    if (!file.read(header, sizeof(header))) {
        throw FileError("cannot write " + finalPath + ": OpenVDB wrote a truncated header");
    }
    int64_t magic = 0;
    uint32_t fileVersion = 0;
    std::memcpy(&magic, header, sizeof(magic));
    std::memcpy(&fileVersion, header + 8, sizeof(fileVersion));
    if (magic != kVdbMagic || fileVersion < openvdb::OPENVDB_FILE_VERSION_BOOST_UUID) {
        throw FileError("cannot write " + finalPath
                        + ": unexpected VDB header layout (file version "
                        + std::to_string(fileVersion) + ")");
    }

    ContentHash hash;
    hash.update(header, kUuidOffset);
    std::array<char, 1 << 16> buffer;
    while (file.read(buffer.data(), buffer.size()) || file.gcount() > 0) {
        hash.update(buffer.data(), static_cast<size_t>(file.gcount()));
    }
    file.clear();
    const std::string uuid = hash.uuid();
    file.seekp(kUuidOffset);
    file.write(uuid.data(), static_cast<std::streamsize>(uuid.size()));
    file.flush();
    if (!file) {
        throw FileError("cannot write " + finalPath + ": " + std::strerror(errno));
    }
}

} // namespace write_vdb_internal

void writeVdb(const openvdb::GridCPtrVec& grids, const std::string& path,
              const openvdb::MetaMap& fileMetadata)
{
    using namespace write_vdb_internal;
    openvdb::initialize(); // idempotent; registers the grid and metadata types

    for (const auto& grid : grids) {
        if (!grid) throw FileError("cannot write " + path + ": null grid");
    }

    // AtomicFile creates the temporary file itself, so a missing directory is reported
    // with errno's reason (io::File would only say "could not open file for writing").
    AtomicFile temp(path);

    try {
        std::ofstream os;
        os.open(temp.tempPath(), std::ios_base::out | std::ios_base::binary | std::ios_base::trunc);
        errno = 0;
        openvdb::MetaMap metadata(fileMetadata);
        if (!metadata["creator"]) {
            metadata.insertMeta("creator", openvdb::StringMetadata(versionLine()));
        }
        if (os) StreamArchive().writeSeekable(os, grids, metadata);
        if (os) os.close();
        if (!os) throw FileError("cannot write " + path + ": " + std::strerror(errno ? errno : EIO));
    } catch (const Error&) {
        throw;
    } catch (const openvdb::Exception& e) {
        throw FileError("cannot write " + path + ": " + e.what());
    } catch (const std::exception& e) {
        throw FileError("cannot write " + path + ": " + e.what());
    }

    makeUuidDeterministic(temp.tempPath(), path);
    temp.commit();
}

} // namespace nonbloppy
