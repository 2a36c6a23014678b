// SPDX-License-Identifier: Apache-2.0
#include "AttributeNames.h"

#include <algorithm>
#include <cctype>
#include <set>

namespace nonbloppy {
namespace attribute_names_internal {

namespace {

/// headerWord() of @a name, keeping ',' and '"' if @a quoted (a CSV field in quotes).
std::string
wordOf(const std::string& name, bool quoted)
{
    std::string word = name.empty() ? std::string("attribute") : name;
    for (char& ch : word) {
        if (static_cast<unsigned char>(ch) <= ' ' || static_cast<unsigned char>(ch) >= 0x7f
            || (!quoted && (ch == ',' || ch == '"')) || ch == '<' || ch == '>' || ch == '&') {
            ch = '_';
        }
    }
    return word;
}

} // namespace

std::string
headerWord(const std::string& name)
{
    return wordOf(name, /*quoted=*/false);
}

std::string
csvWord(const std::string& name)
{
    return wordOf(name, /*quoted=*/true);
}

std::string
vdbWord(const std::string& name)
{
    std::string word = name.empty() ? std::string("attribute") : name;
    for (char& ch : word) {
        if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '|' && ch != ':') ch = '_';
    }
    return word;
}

std::vector<std::string>
wholeColumn(const std::string& base, int)
{
    return {base};
}

std::vector<std::string>
plyColumns(const std::string& base, int components)
{
    if (components == 1) return {base};
    std::vector<std::string> columns;
    for (int c = 0; c < components; ++c) {
        columns.push_back(components == 3 ? base + "_" + "xyz"[c] : base + "_" + std::to_string(c));
    }
    return columns;
}

// Renaming "a b" to "a_b" beside an attribute "a_b" gave two columns of one name, which
// nonbloppy's own readers then refused ("duplicate column"); a mesh attribute "nx" beside
// the normals gave a PLY with two properties "nx", which readers resolve either way.
std::vector<std::string>
uniqueNames(const std::vector<NamedAttribute>& attributes, std::string (*word)(const std::string&),
            const ColumnsOf& columnsOf, const IsReserved& isReserved,
            const ComponentOf& componentOf)
{
    std::set<std::string> taken;
    std::vector<std::string> names(attributes.size());
    for (const bool renamed : {false, true}) {
        for (size_t i = 0; i < attributes.size(); ++i) {
            const auto& [original, components] = attributes[i];
            const std::string base = word(original);
            if ((base != original) != renamed) continue;
            std::string name = base;
            for (int suffix = 2;; ++suffix) {
                const std::vector<std::string> columns = columnsOf(name, components);
                // A vector written as columns also holds the spellings of its next component:
                // a scalar "a_2" beside the 2-component "a" (a_0, a_1) read back as one
                // 3-component "a" and was gone.
                // So does its bare name, without which a reader joins no run of that base.
                std::vector<std::string> claimed = columns;
                if (columns.size() > 1) {
                    claimed.push_back(name);
                    const std::string next = std::to_string(components);
                    for (const std::string& spelling : {name + "_" + next, name + ":" + next, name + "[" + next + "]"}) {
                        claimed.push_back(spelling);
                    }
                }
                if (std::none_of(columns.begin(), columns.end(), isReserved)
                    && std::none_of(claimed.begin(), claimed.end(), [&](const std::string& c) { return taken.count(c); })) {
                    taken.insert(claimed.begin(), claimed.end());
                    break;
                }
                name = base + "_" + std::to_string(suffix);
            }
            names[i] = name;
        }
    }
    // Scalars named like one vector's columns in a row came back from PLY and CSV as that
    // vector (format round-trip hunt: n_x, n_y, n_z as 'n'). The reader joins a run that
    // starts at component 0; the scalar that would continue one gets a suffix.
    if (componentOf) {
        std::string runBase;
        int runNext = -1;  // the component that would continue the run; -1: no run
        for (size_t i = 0; i < attributes.size(); ++i) {
            if (attributes[i].second != 1) {
                runNext = -1;  // a vector's own columns; its next spellings are claimed above
                continue;
            }
            std::string base;
            int component = componentOf(names[i], base);
            if (component > 0 && component == runNext && base == runBase) {
                for (int suffix = 2;; ++suffix) {
                    const std::string candidate = names[i] + "_" + std::to_string(suffix);
                    if (!isReserved(candidate) && taken.insert(candidate).second) {
                        names[i] = candidate;
                        break;
                    }
                }
                component = componentOf(names[i], base);  // n_y_2: component 2 of n_y
            }
            if (component == 0) {
                runBase = base;
                runNext = 1;
            } else {
                runNext = -1;
            }
        }
    }
    return names;
}

} // namespace attribute_names_internal
} // namespace nonbloppy
