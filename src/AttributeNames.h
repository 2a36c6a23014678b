// SPDX-License-Identifier: Apache-2.0
/// @file AttributeNames.h
/// @brief Private: the names particle and mesh writers give attributes in each file format,
///        distinct from one another and from the columns the format already uses.
///        Only src/ includes it.

#ifndef NONBLOPPY_ATTRIBUTE_NAMES_H
#define NONBLOPPY_ATTRIBUTE_NAMES_H

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace nonbloppy {
namespace attribute_names_internal {

/// An attribute's name and its number of components.
using NamedAttribute = std::pair<std::string, int>;

/// The columns (properties, arrays) an attribute called @a base with @a components is
/// written as, in one format.
using ColumnsOf = std::function<std::vector<std::string>(const std::string& base, int components)>;

/// Whether a column name is the format's own (positions, normals) and cannot be taken.
using IsReserved = std::function<bool(const std::string& column)>;

/// The component a column name spells to the format's reader (setting @a base), or -1:
/// io_internal::suffixComponentOf() for PLY, tableComponentOf() for CSV.
using ComponentOf = std::function<int(const std::string& column, std::string& base)>;

/// An attribute name as one header word (PLY, VTK, VTU, CSV): whitespace, control and
/// non-ASCII bytes, ',', '"', '<', '>' and '&' become '_'; an empty name is "attribute".
std::string headerWord(const std::string& name);

/// An attribute name as one CSV header field: headerWord() but for ',' and '"', which
/// writeCsv() quotes (RFC 4180) instead; they came back as '_' before.
std::string csvWord(const std::string& name);

/// An attribute name in OpenVDB's alphabet (letters, digits, '_', '|', ':'), which
/// appendAttribute() enforces by throwing; an empty name is "attribute".
std::string vdbWord(const std::string& name);

/// One column per attribute (VTK and VTU arrays hold all components).
std::vector<std::string> wholeColumn(const std::string& base, int components);

/// PLY properties: name, name_x/_y/_z, or name_<c>.
std::vector<std::string> plyColumns(const std::string& base, int components);

/// The names the attributes are written under: @a word of each name (the format's
/// alphabet), then, if any column it gives is taken (by the format: @a isReserved, or by
/// another attribute), the first of word_2, word_3, ... whose columns are all free.
/// Names the format takes as they are claim theirs first, in order; renamed ones follow,
/// so "a b" beside "a_b" becomes "a_b_2" and "a_b" stays. An attribute written as several
/// columns also claims its bare name and its next component's spellings (name_N, name:N,
/// name[N] for N components), so that no other column joins its run on reading back: a
/// scalar "a_2" beside a 2-component "a" is written as "a_2_2".
/// With @a componentOf, scalars named like the columns of one vector in a row (n_x, n_y,
/// n_z; b_0, b_1), which the reader would join into that vector, are kept apart: the
/// first that would continue such a run gets _2 (n_x, n_y_2, n_z).
/// Cost: O(A log A) set operations for A attributes (times their columns).
std::vector<std::string> uniqueNames(const std::vector<NamedAttribute>& attributes,
                                     std::string (*word)(const std::string&), const ColumnsOf& columnsOf,
                                     const IsReserved& isReserved, const ComponentOf& componentOf = nullptr);

} // namespace attribute_names_internal
} // namespace nonbloppy

#endif // NONBLOPPY_ATTRIBUTE_NAMES_H
