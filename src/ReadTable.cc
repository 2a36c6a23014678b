// SPDX-License-Identifier: Apache-2.0
/// @file ReadTable.cc
/// @brief Text particle tables: CSV/TXT with a header row, and JSON `[[x,y,z], ...]`.
///
/// Table layout: a UTF-8 byte order mark is skipped, and so are lines starting with '#' and
/// blank lines; the first other line names the columns, separated by ',' or ';' or tabs or
/// spaces (the first of these found
/// in the header is the separator), names and values optionally quoted (a separator inside
/// double quotes is no separator; a quote inside them is doubled, RFC 4180). A column
/// without a name (the row numbers pandas and R write first) is left out and listed in
/// ParticleSet::skipped. Positions are the columns
/// x, y, z (any case), or ParaView's `Points:0..2`, or `<name>_x/_y/_z` with name
/// position, pos or p. Every other column is an attribute; consecutive columns
/// `<name>:0,:1,...` (ParaView; up to 100), `<name>[0],[1],...`, `<name>_x,_y,_z` or
/// `<name>.x,.y,.z` form one attribute `<name>` of that many components, unless another
/// column is called `<name>`; a lone `<name>_x` is a scalar of that name. An attribute
/// whose values are all integers is Int64, else Float64.
///
/// Both are read through a StreamReader (a bounded buffer) straight into the final arrays:
/// table rows a buffered block of whole lines at a time, cut into pieces that are parsed
/// in parallel and stored in order as they come, an attribute's values as int64 while
/// every one is a whole number that fits, then as float64 (those before converted) from
/// the first that is not; JSON `[[x, y, z], ...]` with parseDoubleRefusingOverflow(),
/// anything else (errors included) again from the start through nlohmann's SAX parser, with
/// no DOM. The 64x benchmark input as CSV with id and velocity (107 MB), measured side by side:
/// 0.26-0.28 s at two threads, 0.38-0.41 s at one (row by row: 0.35-0.37 s either way); its
/// positions as JSON (51 MB): 0.12-0.13 s (through nlohmann's parser: 0.63-0.65 s).
/// Text has no counts to check; once the first rows show the bytes per particle, the
/// arrays are reserved for the bytes left in the file plus a quarter (re-estimated if that
/// falls short), so they are not copied as they grow.

#include "FileFormats.h"
#include "ParticleReaders.h"
#include "StreamReader.h"

#include <nonbloppy/Error.h>

#include <nlohmann/json.hpp>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <unordered_set>

namespace nonbloppy {
namespace io_internal {

namespace {

/// "coordinate 1e39 on line 3 lies outside float's range (-3.4e38 to 3.4e38)" for a finite
/// coordinate @a text (as written) that becomes infinite as a float, @a where it stands
/// ("on line 3", "of particle 2"): the CSV and JSON readers' one message for it.
std::string beyondFloatMessage(const std::string& text, const std::string& where)
{
    return "coordinate " + text + " " + where + " lies outside float's range (-3.4e38 to 3.4e38)";
}

/// @a text without the spaces, tabs and '\r' around it.
std::string_view
unpadded(std::string_view text)
{
    while (!text.empty() && (text.front() == ' ' || text.front() == '\t' || text.front() == '\r')) text.remove_prefix(1);
    while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r')) text.remove_suffix(1);
    return text;
}

std::string_view
trimmed(std::string_view text)
{
    text = unpadded(text);
    if (text.size() >= 2 && (text.front() == '"' || text.front() == '\'') && text.back() == text.front()) {
        text = text.substr(1, text.size() - 2);
    }
    return text;
}

/// The name a header field gives its column: trimmed(), but inside double quotes as RFC 4180
/// has it, a doubled quote being one ("e""f" names e"f, as writeCsv() writes it; the name
/// kept both) and single quotes part of the name ("'s'" names 's'); only spaces around it
/// go. @a field is as splitLine(..., /*trimFields=*/false) gives it.
std::string
columnName(std::string_view field)
{
    const std::string_view text = unpadded(field);
    // Not in double quotes: trimmed twice, as before (splitLine() trimmed every field, and
    // the header's names were trimmed again), so '"x"' still names x.
    if (text.size() < 2 || text.front() != '"' || text.back() != '"') return std::string(trimmed(trimmed(text)));
    std::string name;
    for (size_t i = 1; i + 1 < text.size(); ++i) {
        name += text[i];
        if (text[i] == '"' && text[i + 1] == '"') ++i;
    }
    return std::string(unpadded(name));
}

/// Split @a line at @a separator (' ' means runs of spaces and tabs); each field trimmed()
/// unless @a trimFields is false (the header, whose names columnName() unquotes).
void
splitLine(std::string_view line, char separator, std::vector<std::string_view>& fields, bool trimFields = true)
{
    fields.clear();
    if (separator == ' ') {
        size_t pos = 0;
        while (pos < line.size()) {
            while (pos < line.size() && (line[pos] == ' ' || line[pos] == '\t' || line[pos] == '\r')) ++pos;
            const size_t start = pos;
            while (pos < line.size() && line[pos] != ' ' && line[pos] != '\t' && line[pos] != '\r') ++pos;
            if (pos > start) fields.push_back(line.substr(start, pos - start));
        }
        return;
    }
    // A separator inside double quotes is part of the field (RFC 4180: a column "a,b");
    // lines without quotes, nearly all, take the fast search.
    const bool quoted = line.find('"') != std::string_view::npos;
    size_t start = 0;
    while (true) {
        size_t end = start;
        if (quoted) {
            bool inQuotes = false;
            while (end < line.size() && (inQuotes || line[end] != separator)) {
                if (line[end] == '"') inQuotes = !inQuotes;
                ++end;
            }
            if (end == line.size()) end = std::string_view::npos;
        } else {
            end = line.find(separator, start);
        }
        const std::string_view field = line.substr(start, end == std::string_view::npos ? end : end - start);
        fields.push_back(trimFields ? trimmed(field) : field);
        if (end == std::string_view::npos) break;
        start = end + 1;
    }
}

struct Column
{
    int attribute = -1;  ///< index into the attribute list, -1 for a position, kUnnamed
    int component = 0;   ///< axis for positions, component for attributes
};

/// Column::attribute of a column without a name: the row numbers pandas' to_csv() and R's
/// write.csv() put first, left out (and said: ParticleSet::skipped).
constexpr int kUnnamed = -2;

/// Appends the 8 native bytes of @a value to @a bytes.
template<typename T>
void
appendBytes(std::vector<unsigned char>& bytes, T value)
{
    static_assert(sizeof(T) == 8, "int64 or float64");
    const unsigned char* raw = reinterpret_cast<const unsigned char*>(&value);
    bytes.insert(bytes.end(), raw, raw + 8);
}

/// Rows read before the arrays are reserved from the bytes per row seen so far.
constexpr size_t kEstimateAfterRows = 1024;

/// True when the arrays, holding @a size items in @a capacity, should be reserved for an
/// estimate of the whole input: after the first rows, and again instead of doubling if the
/// estimate falls short (reserved but untouched room costs address space, not memory).
bool
timeToEstimate(size_t size, size_t capacity)
{
    return size == kEstimateAfterRows || (size > kEstimateAfterRows && size == capacity);
}

/// Room for @a done items read from @a doneBytes, plus what the @a remaining bytes may
/// hold at the same rate, with a quarter more for rows that grow longer (numbers printed
/// with more digits further on).
size_t
estimatedCount(size_t done, uint64_t doneBytes, uint64_t remaining)
{
    const double bytesPerItem = std::max(double(doneBytes) / double(done), 1.0);
    return done + size_t(double(remaining) / bytesPerItem * 1.25) + 16;
}

/// One field of a data row, parsed ahead of the serial pass that stores it, into every
/// reading that pass may ask for (which one it takes depends on the rows before).
struct ParsedField
{
    enum Kind : uint8_t
    {
        Bad,     ///< not a number (an error if the pass needs it)
        Whole,   ///< a whole number that fits int64: whole
        Large,   ///< a whole number past int64 that fits uint64: large
        Number,  ///< any other number: value
    };
    union
    {
        int64_t whole;
        uint64_t large;
        double value;
    };
    Kind kind;
    bool minus;         ///< the text starts with '-' (a "-0" whole number, kept as -0.0 later)
    bool negativeZero;  ///< a Whole 0 whose double is -0.0 ("-0", and "+-0", which parseWhole() takes)

    /// As parseWhole(text, uint64_t&) would read it.
    bool asLarge(uint64_t& out) const
    {
        if (kind == Large) out = large;
        else if (kind == Whole && !minus) out = uint64_t(whole);  // '-' is no uint64: "-0" neither
        else return false;
        return true;
    }
    /// As parseDoubleRefusingOverflow(text, ...) would read it: a whole number's double is
    /// its correctly rounded value either way.
    bool asDouble(double& out) const
    {
        switch (kind) {
        case Whole: out = whole == 0 && negativeZero ? -0.0 : double(whole); return true;
        case Large: out = double(large); return true;
        case Number: out = value; return true;
        default: return false;
        }
    }
};

/// The data rows of one piece of a block of lines (parsePiece()), parsed.
struct RowPiece
{
    struct Row
    {
        size_t start, length;  ///< the row's text in the block
        size_t line;           ///< its line in the piece, 0-based
        size_t fieldCount;     ///< the fields found in it
    };
    size_t lines = 0;                 ///< lines in the piece, rows or not (blank, comments)
    std::vector<Row> rows;
    std::vector<ParsedField> fields;  ///< rows × columns (those of a row of another count unset)
    std::vector<std::string_view> texts;  ///< scratch: the fields of the line being parsed

    void clear()
    {
        lines = 0;
        rows.clear();
        fields.clear();
    }
};

/// Whether @a text has the form parseWhole() accepts: '+'? '-'? digits.
bool
looksWhole(std::string_view text)
{
    size_t at = 0;
    if (at < text.size() && text[at] == '+') ++at;
    if (at < text.size() && text[at] == '-') ++at;
    if (at == text.size()) return false;
    for (; at < text.size(); ++at) {
        if (text[at] < '0' || text[at] > '9') return false;
    }
    return true;
}

/// Where @a block (whole lines, each ended by '\n' but perhaps the last) is cut into
/// @a count pieces of about equal size: piece k is [cut[k], cut[k + 1]), starting at the
/// first line start at or after k/count of the block (a block of fewer bytes than pieces
/// leaves the first ones empty).
std::vector<size_t>
cutAtLines(std::string_view block, size_t count)
{
    std::vector<size_t> cut(count + 1, block.size());
    cut[0] = 0;
    for (size_t k = 1; k < count; ++k) {
        const size_t target = std::max(cut[k - 1], block.size() * k / count);
        if (target == 0) {
            cut[k] = 0;
            continue;
        }
        const size_t newline = block.find('\n', target - 1);  // a line starts at target if one ends before it
        cut[k] = newline == std::string_view::npos ? block.size() : newline + 1;
    }
    return cut;
}

/// Parse the lines of @a block in [@a begin, @a end) (whole lines) into @a piece: each line
/// that is neither blank nor a '#' comment is a row, split at @a separator, its fields
/// parsed as @a columns says (nothing for an unnamed column, a double for a position, and
/// for an attribute a whole number where it is one: ParsedField). A row of another field
/// count is only counted (the caller reports it, in order). Thread-safety: writes @a piece
/// only.
void
parsePiece(std::string_view block, size_t begin, size_t end, char separator, const std::vector<Column>& columns,
           RowPiece& piece)
{
    const size_t width = columns.size();
    piece.clear();
    std::vector<std::string_view>& texts = piece.texts;
    for (size_t at = begin; at < end;) {
        const size_t newline = block.find('\n', at);
        const size_t lineEnd = newline == std::string_view::npos || newline >= end ? end : newline;
        const std::string_view line = block.substr(at, lineEnd - at);
        const size_t lineInPiece = piece.lines++;
        at = lineEnd + 1;
        const std::string_view content = trimmed(line);
        if (content.empty() || content[0] == '#') continue;
        splitLine(line, separator, texts);
        piece.rows.push_back({size_t(line.data() - block.data()), line.size(), lineInPiece, texts.size()});
        piece.fields.resize(piece.fields.size() + width);
        if (texts.size() != width) continue;
        ParsedField* parsed = piece.fields.data() + piece.fields.size() - width;
        for (size_t i = 0; i < width; ++i) {
            if (columns[i].attribute == kUnnamed) continue;
            const std::string_view text = trimmed(texts[i]);
            ParsedField& field = parsed[i];
            field.minus = !text.empty() && text.front() == '-';
            // An attribute may be stored as an integer: parseWhole() takes an optional
            // '+', an optional '-' and digits only, so other text (most: 2.45, 1e-3)
            // is not tried (two from_chars calls per field cost a fifth of the read).
            if (columns[i].attribute >= 0 && looksWhole(text)) {
                if (io_internal::parseWhole(text, field.whole)) {
                    field.kind = ParsedField::Whole;
                    double zero = 0.0;
                    field.negativeZero =
                        field.whole == 0 && parseDoubleRefusingOverflow(text, zero) && std::signbit(zero);
                    continue;
                }
                if (io_internal::parseWhole(text, field.large)) {
                    field.kind = ParsedField::Large;
                    continue;
                }
            }
            field.kind = parseDoubleRefusingOverflow(text, field.value) ? ParsedField::Number : ParsedField::Bad;
        }
    }
}

ParticleSet
parseTable(StreamReader& in, const std::string& path)
{
    size_t lineNumber = 0;
    auto nextLine = [&](std::string_view& line) {
        while (in.line(line)) {
            ++lineNumber;
            // Excel's "CSV UTF-8" starts with a byte order mark, which is no part of a name.
            constexpr std::string_view kByteOrderMark = "\xef\xbb\xbf";
            if (lineNumber == 1 && line.substr(0, kByteOrderMark.size()) == kByteOrderMark) {
                line.remove_prefix(kByteOrderMark.size());
            }
            const std::string_view content = trimmed(line);
            if (content.empty() || content[0] == '#') continue;
            return true;
        }
        return false;
    };

    std::string_view headerLine;
    if (!nextLine(headerLine)) fail(path, "empty table: no header row");
    const std::string header(headerLine);  // the reader's buffer moves on
    // The separator is looked for outside quotes: "x;y;z;\"a,b\"" is separated by ';'.
    std::string unquoted;
    bool inQuotes = false;
    for (const char c : header) {
        if (c == '"') inQuotes = !inQuotes;
        else if (!inQuotes) unquoted += c;
    }
    char separator = ' ';
    for (char candidate : {',', ';', '\t'}) {
        if (unquoted.find(candidate) != std::string::npos) {
            separator = candidate;
            break;
        }
    }
    std::vector<std::string_view> fields;
    splitLine(header, separator, fields, /*trimFields=*/false);

    // Map the columns to positions and attributes (vectors as groupColumns() forms them).
    std::vector<Column> columns(fields.size());
    std::vector<AttributeColumn> attributeColumns;
    int axisColumn[3] = {-1, -1, -1};
    for (size_t i = 0; i < fields.size(); ++i) {
        const std::string name = columnName(fields[i]);
        if (name.empty()) {
            columns[i] = {kUnnamed, 0};
            continue;
        }
        std::string base;
        const int component = tableComponentOf(name, base);
        const int axis = tablePositionAxis(name);
        if (axis >= 0) {
            if (axisColumn[axis] >= 0) fail(path, "two columns for coordinate " + std::string(1, "xyz"[axis]));
            axisColumn[axis] = int(i);
            columns[i] = {-1, axis};
            continue;
        }
        attributeColumns.push_back(AttributeColumn{i, name, base, component});
    }
    if (axisColumn[0] < 0 || axisColumn[1] < 0 || axisColumn[2] < 0) {
        fail(path, "the header must name columns x, y and z, got '" + printable(header) + "'");
    }
    std::vector<std::string> names;
    std::vector<int> componentCounts;
    std::unordered_set<std::string> seen;  // a scan per column made wide headers quadratic
    for (const ColumnGroup& group : groupColumns(attributeColumns)) {
        if (!seen.insert(group.name).second) fail(path, "duplicate column '" + printable(group.name) + "'");
        for (size_t c = 0; c < group.columns.size(); ++c) {
            columns[attributeColumns[group.columns[c]].index] = {int(names.size()), int(c)};
        }
        names.push_back(group.name);
        componentCounts.push_back(int(group.columns.size()));
    }

    // Values go straight into the attribute arrays: as int64 while every value of the
    // attribute is a whole number that fits (parsed as such, so an id past 2^53 stays
    // exact); as uint64 once one passes int64 if none was negative (the bytes of the values
    // before are the same: a CSV of uint64 ids came back rounded, bug hunt); then as float64
    // from the first that fits neither, the integers before it converted.
    // A "-0" is the integer 0 there, and -0.0 once the attribute turns float64 (it came back
    // +0.0, format round-trip hunt): where each lies is kept for that.
    ParticleSet particles;
    particles.attributes.resize(names.size());
    std::vector<ScalarType> kinds(names.size(), ScalarType::Int64);
    std::vector<bool> negative(names.size(), false);
    std::vector<std::vector<size_t>> minusZeroAt(names.size());  // byte offsets
    // One parsed row, stored: its position, and each attribute's value in the type the
    // attribute has so far (see above). @a rowText and @a line are for an error message.
    const auto storeRow = [&](const ParsedField* parsed, size_t line, std::string_view rowText) {
        openvdb::Vec3f p;
        for (size_t i = 0; i < columns.size(); ++i) {
            const ParsedField& field = parsed[i];
            const int attribute = columns[i].attribute;
            if (attribute == kUnnamed) continue;
            if (attribute >= 0 && kinds[size_t(attribute)] != ScalarType::Float64) {
                const size_t a = size_t(attribute);
                if (kinds[a] == ScalarType::Int64 && field.kind == ParsedField::Whole) {
                    negative[a] = negative[a] || field.whole < 0;
                    if (field.whole == 0 && field.minus) minusZeroAt[a].push_back(particles.attributes[a].bytes.size());
                    appendBytes(particles.attributes[a].bytes, field.whole);
                    continue;
                }
                uint64_t large;
                if (!negative[a] && field.asLarge(large)) {
                    kinds[a] = ScalarType::UInt64;
                    appendBytes(particles.attributes[a].bytes, large);
                    continue;
                }
            }
            // The field's text as written, for an error (the row is split again only then).
            const auto fieldText = [&] {
                std::vector<std::string_view> texts;
                splitLine(rowText, separator, texts);
                return printable(trimmed(texts[i]));
            };
            double value;
            if (!field.asDouble(value)) {
                fail(path, "bad number '" + fieldText() + "' on line " + std::to_string(line));
            }
            if (attribute < 0) {
                p[columns[i].component] = static_cast<float>(value);
                if (std::isfinite(value) && !std::isfinite(p[columns[i].component])) {
                    // Positions are float: said here, where the text is known, rather than as
                    // a "non-finite position" that the file does not hold.
                    fail(path, beyondFloatMessage(fieldText(), "on line " + std::to_string(line)));
                }
                continue;
            }
            std::vector<unsigned char>& bytes = particles.attributes[size_t(attribute)].bytes;
            ScalarType& kind = kinds[size_t(attribute)];
            if (kind != ScalarType::Float64) {
                for (size_t at = 0; at < bytes.size(); at += 8) {
                    int64_t signedValue;
                    uint64_t unsignedValue;
                    std::memcpy(&signedValue, bytes.data() + at, 8);
                    std::memcpy(&unsignedValue, bytes.data() + at, 8);
                    const double converted = kind == ScalarType::Int64 ? double(signedValue) : double(unsignedValue);
                    std::memcpy(bytes.data() + at, &converted, 8);
                }
                const double minusZero = -0.0;
                for (const size_t at : minusZeroAt[size_t(attribute)]) std::memcpy(bytes.data() + at, &minusZero, 8);
                minusZeroAt[size_t(attribute)].clear();
                kind = ScalarType::Float64;
            }
            appendBytes(bytes, value);
        }
        particles.positions.push_back(p);
    };

    // The rows are parsed a block of whole lines at a time, straight from the reader's
    // buffer, cut into pieces of about kPieceBytes that go through a TBB pipeline: parsed in
    // parallel (parsePiece(): from_chars was most of the read), then stored in order by one
    // thread, which alone knows each attribute's type so far: the same particles, and the
    // same first error, as parsing row after row. A piece is stored while it is still in
    // the cache, and while the next ones are parsed; the whole block parsed before any of
    // it was stored (1 MiB of text, 1.6 MB of parsed fields) was 7-11% slower than row by
    // row at one thread, and kept the second thread idle while one stored.
    constexpr size_t kPieceBytes = size_t(64) << 10;
    // A piece holds its token from parsing to storing, so piece k + tokens never shares
    // piece k's slot while k is in flight.
    const size_t tokens = 2 * size_t(std::max(1, tbb::this_task_arena::max_concurrency()));
    std::vector<RowPiece> pieces(tokens);
    const uint64_t dataStart = in.pos();
    while (in.ensure(1)) {
        // Whole lines: up to the last '\n' buffered (more is read while there is none),
        // or to the end of the data.
        size_t blockSize = 0;
        for (;;) {
            const size_t last = std::string_view(in.here(), in.available()).rfind('\n');
            if (last != std::string_view::npos) {
                blockSize = last + 1;
                break;
            }
            if (!in.ensure(in.available() + 1)) {
                blockSize = in.available();
                break;
            }
        }
        const std::string_view block(in.here(), blockSize);
        const size_t pieceCount = std::max<size_t>(1, (blockSize + kPieceBytes - 1) / kPieceBytes);
        const std::vector<size_t> cut = cutAtLines(block, pieceCount);
        const auto storePiece = [&](const RowPiece& piece) {
            for (size_t r = 0; r < piece.rows.size(); ++r) {
                const RowPiece::Row& row = piece.rows[r];
                const size_t line = lineNumber + row.line + 1;  // 1-based
                if (row.fieldCount != columns.size()) {
                    fail(path, "line " + std::to_string(line) + " has " + std::to_string(row.fieldCount) +
                         " fields, the header " + std::to_string(columns.size()));
                }
                storeRow(piece.fields.data() + r * columns.size(), line, block.substr(row.start, row.length));
                if (timeToEstimate(particles.positions.size(), particles.positions.capacity())) {
                    // Bytes up to this row's end, and left after it.
                    const uint64_t inBlock = row.start + row.length + 1;
                    const size_t rows = estimatedCount(particles.positions.size(), in.pos() - dataStart + inBlock,
                                                       in.remaining() - std::min<uint64_t>(in.remaining(), inBlock));
                    particles.positions.reserve(rows);
                    for (size_t a = 0; a < names.size(); ++a) {
                        particles.attributes[a].bytes.reserve(rows * size_t(componentCounts[a]) * 8);
                    }
                }
            }
            lineNumber += piece.lines;
        };
        size_t next = 0;
        tbb::parallel_pipeline(tokens,
            tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                [&](tbb::flow_control& control) {
                    if (next == pieceCount) control.stop();
                    return next++;
                }) &
            tbb::make_filter<size_t, size_t>(tbb::filter_mode::parallel,
                [&](size_t k) {
                    parsePiece(block, cut[k], cut[k + 1], separator, columns, pieces[k % tokens]);
                    return k;
                }) &
            tbb::make_filter<size_t, void>(tbb::filter_mode::serial_in_order,
                [&](size_t k) { storePiece(pieces[k % tokens]); }));
        in.advance(blockSize);
    }
    for (size_t i = 0; i < columns.size(); ++i) {
        if (columns[i].attribute == kUnnamed) particles.skipped.push_back("unnamed column " + std::to_string(i + 1));
    }
    for (size_t a = 0; a < names.size(); ++a) {
        ParticleAttribute& attribute = particles.attributes[a];
        attribute.name = names[a];
        attribute.components = componentCounts[a];
        attribute.type = kinds[a];
    }
    return particles;
}

} // namespace

ParticleSet
readTableParticles(const char* data, size_t size, const std::string& path)
{
    StreamReader in(data, size, path, /*inflateGzip=*/false);
    return parseTable(in, path);
}

ParticleSet
readTableFile(const std::string& path)
{
    StreamReader in(path, /*inflateGzip=*/false);
    return parseTable(in, path);
}

namespace {

/// SAX handler for `[[x,y,z], ...]`: nothing but numbers two levels deep, three per inner
/// array; no DOM is built, so memory is the particles only.
class JsonPointsHandler : public nlohmann::json_sax<nlohmann::json>
{
public:
    explicit JsonPointsHandler(StreamReader& in) : mIn(in) {}

    std::vector<openvdb::Vec3f> positions;
    std::string error;
    uint32_t recentChars = 0;  ///< the last three bytes parsed (StreamReader::CharIterator)

    bool number(double value)
    {
        if (mDepth != 2) return reject("expected an array of [x, y, z] arrays");
        if (mComponent >= 3) return reject("particle " + std::to_string(positions.size()) + " has more than 3 coordinates");
        mPoint[mComponent] = static_cast<float>(value);
        if (std::isfinite(value) && !std::isfinite(mPoint[mComponent])) {
            char text[32];
            const std::string shortest(text, std::to_chars(text, text + sizeof(text), value).ptr);
            return reject(beyondFloatMessage(shortest, "of particle " + std::to_string(positions.size())));
        }
        ++mComponent;
        return true;
    }
    bool null() override { return reject("null where a coordinate was expected" + inParticle()); }
    bool boolean(bool) override { return reject("boolean where a coordinate was expected" + inParticle()); }
    bool number_integer(number_integer_t value) override
    {
        // nlohmann hands "-0" over as the integer 0, its text gone: a coordinate -0 came back
        // +0 while -0.0 kept its sign (format round-trip hunt). The parser has read the
        // number and the one character after it; a 0 with '-' before it was "-0".
        const bool minusZero = value == 0 && (recentChars >> 8) == ((uint32_t('-') << 8) | uint32_t('0'));
        return number(minusZero ? -0.0 : double(value));
    }
    bool number_unsigned(number_unsigned_t value) override { return number(double(value)); }
    bool number_float(number_float_t value, const string_t&) override { return number(value); }
    bool string(string_t&) override { return reject("string where a coordinate was expected" + inParticle()); }
    bool binary(binary_t&) override { return reject("binary value where a coordinate was expected" + inParticle()); }
    bool start_object(std::size_t) override { return reject("object where an array was expected"); }
    bool key(string_t&) override { return reject("object where an array was expected"); }
    bool end_object() override { return reject("object where an array was expected"); }
    bool start_array(std::size_t) override
    {
        if (++mDepth > 2) return reject("arrays nested deeper than [[x, y, z], ...]");
        mComponent = 0;
        return true;
    }
    bool end_array() override
    {
        if (mDepth == 2) {
            if (mComponent != 3) {
                return reject("particle " + std::to_string(positions.size()) + " has " +
                              std::to_string(mComponent) + " coordinates, expected 3");
            }
            positions.push_back(mPoint);
            if (timeToEstimate(positions.size(), positions.capacity())) {
                positions.reserve(estimatedCount(positions.size(), mIn.pos(), mIn.remaining()));
            }
        }
        --mDepth;
        return true;
    }
    bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& e) override
    {
        // e.what() is "[json.exception.parse_error.101] parse error at line 1, column 2: ..."
        std::string message = e.what();
        const size_t bracket = message.find("] ");
        if (bracket != std::string::npos) message = message.substr(bracket + 2);
        for (char& c : message) {
            if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
        }
        return reject(message + " (byte " + std::to_string(position) + ")");
    }

private:
    /// " (coordinate 2 of particle 7)" inside a particle's array, else "": which value it was,
    /// as the other messages say (hostile-input audit).
    std::string inParticle() const
    {
        if (mDepth != 2) return std::string();
        return " (coordinate " + std::to_string(mComponent) + " of particle " + std::to_string(positions.size()) + ")";
    }

    bool reject(const std::string& message)
    {
        if (error.empty()) error = message;
        return false;
    }

    StreamReader& mIn;
    int mDepth = 0;
    int mComponent = 0;
    openvdb::Vec3f mPoint;
};

/// JSON whitespace.
inline bool isJsonSpace(char c)
{
    return c == ' ' || c == '\n' || c == '\r' || c == '\t';
}

/// The end of the JSON number at @a p (RFC 8259: -? (0 | [1-9] digits) (. digits)?
/// ([eE] [+-]? digits)?), or null if none starts there or it reaches @a end.
inline const char* jsonNumberEnd(const char* p, const char* end)
{
    const auto digits = [&](const char* q) {
        while (q < end && *q >= '0' && *q <= '9') ++q;
        return q;
    };
    if (p < end && *p == '-') ++p;
    if (p == end) return nullptr;
    if (*p == '0') {
        ++p;
    } else if (*p >= '1' && *p <= '9') {
        p = digits(p + 1);
    } else {
        return nullptr;
    }
    if (p < end && *p == '.') {
        const char* after = digits(p + 1);
        if (after == p + 1) return nullptr;
        p = after;
    }
    if (p < end && (*p == 'e' || *p == 'E')) {
        ++p;
        if (p < end && (*p == '+' || *p == '-')) ++p;
        const char* after = digits(p);
        if (after == p) return nullptr;
        p = after;
    }
    return p < end ? p : nullptr;  // a number is followed by something: ',', ']' or space
}

/// The particle list without nlohmann, for the layout of nearly every file: `[[x, y, z],
/// ...]` with JSON whitespace and numbers, read as they come with
/// parseDoubleRefusingOverflow(). True with every position read; false as soon as the text
/// is anything else (an error, or JSON this path leaves to nlohmann: a byte order mark, a
/// particle longer than 4 KB with its spaces, a number past the largest double), @a
/// positions then partly filled. The values
/// are nlohmann's: a number's double is correctly rounded by from_chars (or, below the
/// smallest double, strtod) as by nlohmann's strtod, an integer's is the integer rounded the
/// same way, and "-0" is -0.0 either way. nlohmann read the 64x benchmark
/// input's positions (51 MB) in 0.63 s through this reader (0.56 s from memory), about half
/// a frame's meshing; this path in 0.12 s.
bool
readJsonFast(StreamReader& in, std::vector<openvdb::Vec3f>& positions)
{
    // Each particle is parsed from a window of at least kWindow bytes (or the rest of the
    // data), refilled before it: a particle that does not fit is left to nlohmann.
    constexpr size_t kWindow = 4096;
    const char* p = nullptr;
    const char* end = nullptr;
    bool atDataEnd = false;
    const auto refill = [&] {
        if (p) in.advance(size_t(p - in.here()));
        atDataEnd = !in.ensure(kWindow);
        p = in.here();
        end = p + in.available();
    };
    const auto skipSpace = [&] {
        while (p < end && isJsonSpace(*p)) ++p;
    };
    const auto expect = [&](char c) {
        skipSpace();
        if (p == end || *p != c) return false;
        ++p;
        return true;
    };
    refill();
    if (!expect('[')) return false;
    skipSpace();
    if (p < end && *p == ']') {
        ++p;
    } else {
        for (;;) {
            refill();
            if (!expect('[')) return false;
            openvdb::Vec3f point;
            for (int axis = 0; axis < 3; ++axis) {
                if (axis > 0 && !expect(',')) return false;
                skipSpace();
                const char* numberEnd = jsonNumberEnd(p, end);
                if (!numberEnd) return false;
                double value;
                if (!parseDoubleRefusingOverflow(std::string_view(p, size_t(numberEnd - p)), value)) return false;
                point[axis] = static_cast<float>(value);
                if (!std::isfinite(point[axis])) return false;  // beyond float: nlohmann's path says so
                p = numberEnd;
            }
            if (!expect(']')) return false;
            positions.push_back(point);
            if (timeToEstimate(positions.size(), positions.capacity())) {
                const uint64_t ahead = uint64_t(p - in.here());  // read, not yet advanced past
                const uint64_t left = in.remaining() - std::min(in.remaining(), ahead);
                positions.reserve(estimatedCount(positions.size(), in.pos() + ahead, left));
            }
            skipSpace();
            if (p == end) return false;
            if (*p == ']') {
                ++p;
                break;
            }
            if (*p != ',') return false;
            ++p;
        }
    }
    // Nothing but whitespace after the list.
    for (;;) {
        skipSpace();
        if (p < end) return false;
        if (atDataEnd) return true;
        refill();
        if (p == end) return true;
    }
}

ParticleSet
readJson(StreamReader& in, const std::string& path)
{
    {
        ParticleSet particles;
        if (readJsonFast(in, particles.positions)) return particles;
    }
    // Not the usual layout, or not valid: nlohmann parses it from the start, and accepts it
    // or says why (its messages name the line and column).
    in.rewind();
    JsonPointsHandler handler(in);
    const bool ok = nlohmann::json::sax_parse(StreamReader::CharIterator(in, &handler.recentChars), StreamReader::CharIterator(),
                                              &handler, nlohmann::json::input_format_t::json, true);
    if (!ok || !handler.error.empty()) {
        fail(path, "bad JSON particle list: " + (handler.error.empty() ? "parse error" : handler.error));
    }
    ParticleSet particles;
    particles.positions = std::move(handler.positions);
    return particles;
}

} // namespace

ParticleSet
readJsonParticles(const char* data, size_t size, const std::string& path)
{
    StreamReader in(data, size, path, /*inflateGzip=*/false);
    return readJson(in, path);
}

ParticleSet
readJsonFile(const std::string& path)
{
    StreamReader in(path, /*inflateGzip=*/false);
    return readJson(in, path);
}

} // namespace io_internal
} // namespace nonbloppy
