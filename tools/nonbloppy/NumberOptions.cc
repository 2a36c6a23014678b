// SPDX-License-Identifier: Apache-2.0
#include "NumberOptions.h"

#include "Commands.h"

#include <nonbloppy/CropParticles.h>
#include <nonbloppy/Error.h>

#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace nonbloppy_tool {

void readDecimalOnly(CLI::Option* option, bool integer)
{
    option->transform(
        [name = option->get_name(), integer](const std::string& given) {
            std::string value = given;
            if (value.empty()) return value;
            const size_t unsignedStart = (value[0] == '+' || value[0] == '-') ? 1 : 0;
            bool decimal = false;
            if (integer) {
                decimal = value.size() > unsignedStart
                          && value.find_first_not_of("0123456789", unsignedStart) == std::string::npos;
                if (decimal) {
                    // Leading zeros off, one digit kept: strtoll must not see an octal number.
                    const size_t keep = std::min(value.find_first_not_of('0', unsignedStart), value.size() - 1);
                    value.erase(unsignedStart, keep - unsignedStart);
                }
            } else {
                // std::from_chars reads strtod's decimal forms, inf and nan, and no hexadecimal,
                // no blanks and no '+' (skipped here, once); nor nan's "(chars)", refused as before.
                const char* first = value.data() + (value[0] == '+' ? 1 : 0);
                const char* last = value.data() + value.size();
                double parsed = 0.0;
                const auto [end, error] = std::from_chars(first, last, parsed);
                decimal = end == last && (error == std::errc() || error == std::errc::result_out_of_range)
                          && !(value[0] == '+' && first < last && *first == '-')  // "+-1"
                          && value.find('(') == std::string::npos;
            }
            if (!decimal) {
                throw UsageError(name + " needs " + (integer ? "an integer" : "a number") + ", got '" + value + "'");
            }
            return value;
        },
        "", "");
}

void requireNumberText(const CLI::Option* option, bool real, bool infinityAllowed)
{
    for (const std::string& value : option->results()) {
        if (value.find_first_not_of(" \t") == std::string::npos) {
            throw UsageError(option->get_name() + " needs a number, got ''");
        }
        if (!real) continue;
        errno = 0;
        const double parsed = std::strtod(value.c_str(), nullptr);
        if (infinityAllowed && parsed > 0.0) continue;
        if (errno == ERANGE && (parsed == 0.0 || std::isinf(parsed))) {
            throw UsageError(option->get_name() + " " + value + " lies outside double's range (it reads as " +
                             (parsed == 0.0 ? "0" : parsed > 0.0 ? "infinity" : "-infinity") + ")");
        }
    }
}

void ParticleBoxOption::add(CLI::App* command, const std::string& what)
{
    option = command->add_option("--particle-box", values,
        "Only the particles inside the box X0 Y0 Z0 X1 Y1 Z1 (minimum, then maximum corner), its faces "
        "included, in world units (a tank's walls and floor left out, say); " + what)
        ->expected(6)->type_name("FLOAT")->group(kGroupInputOutput);
    readDecimalOnly(option, /*integer=*/false);
}

std::optional<openvdb::BBoxd> ParticleBoxOption::box() const
{
    if (!option || option->count() == 0) return std::nullopt;
    requireNumberText(option, /*real=*/true);
    const openvdb::BBoxd box(openvdb::Vec3d(values[0], values[1], values[2]),
                             openvdb::Vec3d(values[3], values[4], values[5]));
    try {
        nonbloppy::checkParticleBox(box);
    } catch (const nonbloppy::ParameterError& e) {
        // "particle box: its minimum y 2 exceeds its maximum 1", named as the option.
        const std::string message = e.what();
        throw UsageError("--particle-box" + message.substr(message.find(':')));
    }
    return box;
}

std::string formatBox(const openvdb::BBoxd& box)
{
    return formatPoint<double>(box.min()) + " -> " + formatPoint<double>(box.max());
}

} // namespace nonbloppy_tool
