// SPDX-License-Identifier: Apache-2.0
/// @file FileFormats.h
/// @brief Private parsers shared by readParticles() and readMesh(): whole-file loading, a
///        bounds-checked text cursor, and legacy VTK and PLY decoders that return plain
///        arrays. Nothing here is public API.
///
/// Every parser reads a ByteInput (a buffer holding the whole file, or the file stream of
/// ReadParticles.cc), checks every count against the bytes left before allocating, and
/// reports problems as one-line FileErrors ending in "(<path>)", so no byte sequence can
/// make it crash, hang or allocate without bound. The text and type helpers here are the
/// only copies; the streaming readers use them too.

#ifndef NONBLOPPY_FILE_FORMATS_H
#define NONBLOPPY_FILE_FORMATS_H

#include <nonbloppy/Particles.h>

#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace nonbloppy {
namespace io_internal {

/// A file opened for reading, with what fstat() said of it.
struct OpenFile
{
    int fd = -1;
    bool regular = false;   ///< a regular file, whose size means something
    uint64_t size = 0;      ///< st_size
};

/// Open @a path for reading (the caller closes OpenFile::fd).
/// @throw FileError "cannot open <path>: <reason>", or "cannot read <path>: <reason>" if
///        fstat fails or @a path is a directory.
OpenFile openFile(const std::string& path);

/// Throw FileError("cannot read <path>: <strerror(errorNumber)>").
[[noreturn]] void failRead(const std::string& path, int errorNumber);

/// The whole contents of @a path.
/// @throw FileError "cannot open <path>: <reason>" or "cannot read <path>: <reason>".
std::vector<char> loadFile(const std::string& path);

/// The start of @a path: read in 64 KiB pieces until a piece holds @a marker with the
/// line it ends complete (then what was read), or to the end of the file. For a header
/// whose last line is @a marker (PLY's "end_header"), without reading the data after it.
/// @throw FileError "cannot open <path>: <reason>" or "cannot read <path>: <reason>".
std::vector<char> loadFileThrough(const std::string& path, std::string_view marker);

/// Everything left to read from the open descriptor @a fd (named @a path in errors), in a
/// buffer first sized for @a sizeHint bytes (0: unknown, as for a pipe); closes @a fd
/// whatever happens. Readers use it for pipes, which have no size and must not be opened
/// a second time (that would break the writer's pipe).
/// @throw FileError "cannot read <path>: <reason>".
std::vector<char> readToEndAndClose(int fd, const std::string& path, size_t sizeHint);

/// The extension of the last path component, lower-cased, with its dot (".vtk"), or "".
std::string lowerExtension(const std::string& path);

/// True for the lower-case extensions of the mesh formats: ".obj", ".ply", ".vtk".
bool isMeshExtension(const std::string& ext);

/// lowerExtension() of @a path, which must name a mesh format readMesh() and writeMesh()
/// both know (.obj, .ply, .vtk). The one copy of the check behind requireMeshFile().
/// @throw FileError "mesh file name has no extension (<path>); expected .obj, .ply or .vtk",
///        or "unknown mesh file extension '<ext>' (<path>); expected .obj, .ply or .vtk"
std::string requireMeshExtension(const std::string& path);

/// Throw FileError("<what> (<path>)").
[[noreturn]] void fail(const std::string& path, const std::string& what);

/// Throw FileError("<count> particles would take <bytes> of memory, more than the <headroom>
/// this process can still take (<path>)") if @a count particles of @a bytesPerParticle each
/// exceed machine_memory_internal::memoryHeadroomBytes(): a file that holds more particles
/// than fit in memory is refused before its arrays are allocated, naming the file, instead
/// of ending in std::bad_alloc ("out of memory") or the kernel's OOM killer. Nothing where
/// the headroom is unknown. Cost: a few small reads under /proc and /sys.
void requireMemoryForParticles(const std::string& path, uint64_t count, uint64_t bytesPerParticle);

/// @a text made safe for a one-line message: at most @a maxLength characters (then "..."),
/// non-printable bytes replaced by '?'.
std::string printable(std::string_view text, size_t maxLength = 40);

/// If the table (CSV/TXT) column @a name is "<base><suffix>" with suffix one of the
/// component spellings (_x .x, _y .y, _z .z, any case, for 0 to 2, or :c [c] for any c
/// below kMaxFileComponents, no leading zero, as ParaView and writeParticles() spell components past the third), the
/// component, with @a base set; else -1.
int tableComponentOf(const std::string& name, std::string& base);

/// The component a property or attribute name spells as nonbloppy's writers write the
/// components of vectors in PLY and .vdb: "<base>_x/_y/_z" (0 to 2) or "<base>_<c>" (c
/// below kMaxFileComponents, no leading zero), with @a base set; -1 otherwise.
int suffixComponentOf(const std::string& name, std::string& base);

/// The axis (0..2) a table column named @a name holds: x, y or z, or a component of
/// Points, position, pos or p (any case, e.g. "Points:0", "P_y"); -1 for an attribute
/// column. The reader takes these as positions, so the writer must not name attributes so.
int tablePositionAxis(const std::string& name);

/// An attribute column of a record (CSV) or a vertex property (PLY), as groupColumns()
/// sees it.
struct AttributeColumn
{
    size_t index;        ///< position in the record; a run needs consecutive ones
    std::string name;    ///< as written
    std::string base;    ///< the name without its component spelling ("v" of "v_y")
    int component = -1;  ///< the component that spelling names (1 for "v_y"), or -1
    int kind = 0;        ///< columns of another kind never join (PLY: the value type)
};

/// One attribute made of columns: @a columns index into groupColumns()' argument, in
/// component order.
struct ColumnGroup
{
    std::string name;
    std::vector<size_t> columns;
};

/// The attributes that @a columns form, in order. A run of consecutive columns of one kind
/// that spell components 0, 1, 2, ... of one base is one attribute named by the base; a
/// run of one keeps its column's own name ("speed_x" alone is no vector), as does every
/// column of a run whose base is another column's name ("v" beside "v_x,v_y,v_z"), so that
/// columns a writer spelled apart read back apart. Cost: O(n²) name comparisons for n
/// columns (a header's worth).
std::vector<ColumnGroup> groupColumns(const std::vector<AttributeColumn>& columns);

// ------------------------------------------------------------------------------------------
// Text and value helpers shared by the in-memory parsers here and the streaming readers in
// ReadParticles.cc (so that both accept the same text and say the same words).

constexpr bool kHostIsBigEndian = (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__);

/// Bytes a streaming reader reads from its file at a time; also the bound on temporary
/// conversion buffers (ValueReader::readFloats()).
constexpr size_t kChunkBytes = size_t(1) << 20;

/// The six ASCII white-space characters of isspace() in the C locale (inline: tokenizers
/// call it for every byte).
inline bool isSpace(char ch)
{
    return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r' || ch == '\v' || ch == '\f';
}

/// ASCII lower case; other bytes unchanged.
inline char toLower(char ch)
{
    return (ch >= 'A' && ch <= 'Z') ? char(ch - 'A' + 'a') : ch;
}

/// ASCII case-insensitive equality.
bool iequals(std::string_view a, std::string_view b);

/// @a text without leading and trailing white space.
std::string_view trim(std::string_view text);

/// The white-space separated words of @a text.
std::vector<std::string_view> splitWords(std::string_view text);

/// A whole decimal number of a type std::from_chars reads (integer or floating point), with
/// an optional leading '+'; false if anything else is in @a text.
template<typename NumberT>
bool parseWhole(std::string_view text, NumberT& value)
{
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    const char* end = text.data() + text.size();
    const auto result = std::from_chars(text.data(), end, value);
    return !text.empty() && result.ec == std::errc() && result.ptr == end;
}

/// @a text (an optional '+', then what std::from_chars takes) as a double, in the C locale
/// whatever the process's: std::strtod, the fallback for values out of double's range,
/// follows setlocale(), and under a host application's comma-decimal locale it read
/// "1.5e-400" as 1 (API review). Returns std::errc() for a value in range;
/// std::errc::result_out_of_range with @a value the correctly rounded denormal or 0 below
/// the smallest double, ±inf above the largest; std::errc::invalid_argument unless all of
/// @a text is one number.
std::errc parseDoubleText(std::string_view text, double& value);

/// parseDoubleText(), taking 0 or a denormal below the smallest double but refusing a
/// value above the largest: ±inf there would hide a corrupt file.
inline bool parseDoubleRefusingOverflow(std::string_view text, double& value)
{
    const std::errc parsed = parseDoubleText(text, value);
    return parsed == std::errc() || (parsed == std::errc::result_out_of_range && std::isfinite(value));
}

/// A whole decimal unsigned count (no sign, nothing after it).
bool parseCount(std::string_view text, uint64_t& value);

/// One text value of @a type (optional '+'; out-of-range floats become 0 or inf) into native
/// bytes at @a out; false if @a text is not a whole value of that type.
bool parseTextValue(std::string_view text, ScalarType type, unsigned char* out);

/// Reverse the bytes of each of @a count values of @a width (1, 2, 4 or 8) bytes at @a data.
void swapInPlace(unsigned char* data, size_t count, size_t width);

/// Integer value of @a p (native bytes of integer @a type); false if it does not fit int64.
bool integerValue(const unsigned char* p, ScalarType type, int64_t& value);

/// The type integers within [@a lowest, @a highest] are written as in PLY, which has no
/// 64-bit integers: Int32, else UInt32, where every one fits (exact), else Float64 (exact
/// within ±2^53). An empty range (lowest > highest) gives Int32.
ScalarType plyIntegerType(int64_t lowest, int64_t highest);

/// The PLY property type name of @a type ("float", "int", ...); "double" for the 64-bit
/// integers, which PLY lacks (see plyIntegerType()).
const char* plyTypeName(ScalarType type);

/// The legacy VTK data type name of @a type ("float", "unsigned_int", "vtktypeint64", ...).
const char* vtkTypeName(ScalarType type);

/// The most components an attribute has in a particle or mesh file: the readers refuse
/// more (as a bad header), and the writers refuse to write more (requireFileComponents()).
constexpr int kMaxFileComponents = 4096;

/// @throw ParameterError("attribute 'q' has 5000 components, more than the 4096 a file
///        holds", then @a suffix) if @a components exceeds kMaxFileComponents.
void requireFileComponents(const std::string& name, int components, const std::string& suffix);

/// @throw ParameterError("attribute 'id' has -1 components, at least 1 needed" or "attribute
///        'id' has the unknown scalar type 17", then @a suffix) for an attribute whose values
///        cannot be counted; a caller's struct gave "has 0 values for 2000 particles".
void requireCountableValues(const ParticleAttribute& attribute, const std::string& suffix = "");

/// @throw ParameterError("attribute 'id' does not hold one value per particle", then
///        @a suffix) for the first attribute of @a particles whose bytes are not exactly one
///        value (of its components and type) per particle, after requireCountableValues().
///        What writeParticles() and cropParticles() require of a caller's set.
void requireOneValuePerParticle(const ParticleSet& particles, const std::string& suffix = "");

/// @throw ParameterError("attribute 'h' holds 18446744073709551615, above
///        9223372036854775807, the largest integer @a holder") if @a attribute is UInt64
///        and holds a value no int64 can (@a holder: "a .vdb stores", "a mesh attribute holds").
void requireInt64Values(const ParticleAttribute& attribute, const char* holder);

/// Metadata of a points grid writeParticles() made: the names, separated by spaces, of the
/// attributes it wrote as scalars name_0, name_1, ... (OpenVDB has no type of their
/// component count), which readParticles() joins again.
constexpr const char* kSplitAttributesKey = "nonbloppy_split_attributes";

/// The largest magnitude up to which a double holds every integer (2^53).
constexpr int64_t kExactInDouble = int64_t(1) << 53;
/// True if a double holds @a value exactly: |value| <= 2^53 (past it, doubles skip integers).
constexpr bool exactInDouble(int64_t value) { return value >= -kExactInDouble && value <= kExactInDouble; }

/// Whether 64-bit integer attribute @a attribute (Int64 or UInt64; false for other types)
/// holds a value past ±kExactInDouble, which a double rounds.
bool holdsIntegersPastDouble(const ParticleAttribute& attribute);

/// The native value of @a type at @a p as double.
double valueAsDouble(const unsigned char* p, ScalarType type);

/// @a text with ASCII lower-case letters made upper case.
std::string upper(std::string_view text);

/// Map a PLY property type name ("uchar", "float32", ...) to a ScalarType.
bool plyScalarType(std::string_view name, ScalarType& type);

/// Map a legacy VTK data type name (case-insensitive: "float", "vtktypeint64", ...) to a
/// ScalarType.
bool vtkScalarType(std::string_view name, ScalarType& type);

/// A VTK 5 array name with its %XX escapes decoded.
std::string decodeVtkName(std::string_view name);

// ------------------------------------------------------------------------------------------
// Inputs and typed values

/// Where the parsers read from: a memory buffer (here) or a file stream (ReadParticles.cc).
/// Every access stops at the end of the input.
class ByteInput
{
public:
    virtual ~ByteInput() = default;

    /// Bytes left from the read position to the end of the input.
    virtual uint64_t remaining() const = 0;
    virtual bool atEnd() = 0;
    virtual void skipSpace() = 0;
    /// The next run of non-space characters (empty at the end); valid until the next call.
    virtual std::string_view token() = 0;
    /// The rest of the current line without its line break ("\n" or "\r\n"); moves past it.
    virtual std::string line() = 0;
    /// True if the next non-space text is the word @a word (case-insensitive). Moves nothing.
    virtual bool peekWord(std::string_view word) = 0;
    /// If the next bytes (after white space when @a skipSpaceFirst) are @a word
    /// (case-insensitive), move past the rest of that line and return true. Otherwise
    /// return false having moved nothing, except that an input that cannot move back (the
    /// file stream) has then moved past the white space.
    virtual bool skipLineStartingWith(std::string_view word, bool skipSpaceFirst) = 0;
    /// Copy the next @a n bytes to @a dst; false if the input ends first.
    virtual bool readBytes(unsigned char* dst, size_t n) = 0;
    /// Move @a n bytes ahead (at most to the end).
    virtual void skipBytes(uint64_t n) = 0;
};

/// Reads typed value arrays from a ByteInput, text or binary, never past its end; every
/// problem is a FileError "<what> in <section> (<path>)" or "truncated <section> (<path>)".
class ValueReader
{
public:
    ValueReader(ByteInput& input, bool binary, bool bigEndian, const std::string& path)
        : mInput(input), mBinary(binary), mSwap(binary && bigEndian != kHostIsBigEndian)
        , mPath(path) {}

    bool binary() const { return mBinary; }
    /// True if binary values are byte-swapped to native order.
    bool swaps() const { return mSwap; }

    /// Fail with "truncated <section> (path)" unless @a count values of @a type can still
    /// be in the input: checked before allocating, so a corrupt count cannot exhaust memory.
    void requireRoom(uint64_t count, ScalarType type, const std::string& section) const;

    /// @a count values of @a type, in native byte order, appended to @a out (allocated
    /// only once the input can hold them).
    void read(uint64_t count, ScalarType type, const std::string& section,
              std::vector<unsigned char>& out);

    /// @a count values into @a dst (room for count × scalarSize(type) bytes).
    void readInto(size_t count, ScalarType type, const std::string& section, unsigned char* dst);

    /// @a count Float32 or Float64 values as floats into @a dst; doubles go through a
    /// bounded buffer.
    void readFloats(size_t count, ScalarType type, const std::string& section, float* dst);

    /// Move past @a count values of @a type without keeping them.
    void skip(uint64_t count, ScalarType type, const std::string& section);

    /// One value of integer @a type (e.g. a PLY list length).
    int64_t readInteger(ScalarType type, const std::string& section);

private:
    ByteInput& mInput;
    bool mBinary;
    bool mSwap;
    const std::string& mPath;
};

/// One array of values from a file, converted to native byte order but kept in its type.
struct NumericArray
{
    std::string name;
    std::string kind;      ///< VTK section it came from ("SCALARS", "NORMALS", "FIELD", ...)
    ScalarType type = ScalarType::Float32;
    int components = 1;
    std::vector<unsigned char> bytes;  ///< tuples × components values
};

/// Polygons as offsets into a flat index list: polygon i uses
/// indices[offsets[i]] ... indices[offsets[i+1]-1].
struct PolygonList
{
    std::vector<size_t> offsets{0};
    std::vector<uint32_t> indices;
    size_t size() const { return offsets.size() - 1; }
};

/// What parseVtk() found in a legacy VTK file.
struct VtkData
{
    std::vector<openvdb::Vec3f> points;       ///< POINTS (double converted to float)
    std::vector<NumericArray> pointArrays;    ///< every POINT_DATA array, in file order
    PolygonList polygons;                     ///< POLYGONS, only if asked for
    /// The surface sections not kept, "POLYGONS section", "LINES section", "TRIANGLE_STRIPS
    /// section" (declaring at least one cell; POLYGONS when kept is not listed).
    std::vector<std::string> skippedSections;
};

/// Decode a legacy VTK file (ASCII or big-endian BINARY; version 2 to 5.1 cell layouts;
/// DATASET UNSTRUCTURED_GRID or POLYDATA). Cell sections are skipped unless
/// @a wantPolygons, in which case POLYGONS are kept.
VtkData parseVtk(const char* data, size_t size, const std::string& path, bool wantPolygons);

/// parseVtk() reading from @a input (readParticles() passes a file stream).
VtkData parseVtk(ByteInput& input, const std::string& path, bool wantPolygons);

/// Whether a legacy VTK file has a POLYGONS section header declaring at least one polygon,
/// however broken the file is after it (false when it breaks before), or one of no polygon
/// in a file without points (an empty mesh).
bool vtkDeclaresPolygons(const char* data, size_t size, const std::string& path);

/// What parsePly() found in a PLY file.
struct PlyData
{
    size_t vertexCount = 0;
    std::vector<NumericArray> vertexProperties;  ///< scalar vertex properties, 1 component each
    PolygonList faces;                           ///< face vertex_indices, only if asked for
};

struct PlyProperty
{
    std::string name;
    ScalarType type = ScalarType::Float32;   ///< value type (of the items, for lists)
    bool isList = false;
    ScalarType countType = ScalarType::UInt8;
};

struct PlyElement
{
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

/// The parts of PLY decoding that do not depend on where vertices go: the header, room
/// checks before allocating, and skipping lists and elements. parsePly() and the streaming
/// particle reader derive from it.
class PlyReaderBase
{
protected:
    PlyReaderBase(ByteInput& input, const std::string& path) : mInput(input), mPath(path) {}

    /// Read the header up to end_header into mElements and make mReader.
    void readHeader();
    [[noreturn]] void badHeader(std::string_view line) const;
    /// Fail unless @a element's records can fit in the bytes left (before allocating).
    void requireRoom(const PlyElement& element, const std::string& section) const;
    /// Fail unless the vertex @a element has scalar x, y and z properties.
    void requireAxes(const PlyElement& element) const;
    void skipList(const PlyProperty& property, const std::string& section);
    void skipElement(const PlyElement& element);

    ByteInput& mInput;
    const std::string& mPath;
    std::unique_ptr<ValueReader> mReader;
    std::vector<PlyElement> mElements;
};

/// Decode a PLY file (ascii, binary_little_endian or binary_big_endian).
/// List properties of the vertex element, and every other element, are skipped, except
/// the face element's vertex_indices (or vertex_index) list when @a wantFaces.
PlyData parsePly(const char* data, size_t size, const std::string& path, bool wantFaces);

/// Whether a PLY header declares a face element of at least one face, or any face element
/// and no vertices (an empty mesh; false when the header cannot be read); reads the header
/// only.
bool plyDeclaresFaces(const char* data, size_t size, const std::string& path);

/// The values of a 1- or 3-component array as floats (for positions and normals).
std::vector<float> toFloats(const NumericArray& array);

} // namespace io_internal
} // namespace nonbloppy

#endif // NONBLOPPY_FILE_FORMATS_H
