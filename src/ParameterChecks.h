// SPDX-License-Identifier: Apache-2.0
/// @file ParameterChecks.h
/// @brief One wording, across the library, for a length that must be positive and finite,
///        a step cap, and an enumerator out of range.
#pragma once

#include <nonbloppy/CorrectSurface.h>
#include <nonbloppy/Error.h>

#include "NumberText.h"

#include <cmath>
#include <sstream>
#include <string>

namespace nonbloppy {
namespace parameter_checks_internal {

/// Returns if @a value is finite and > 0.
/// @throw ParameterError "NAME must be finite, got inf" (or nan), else "NAME must be > 0,
///        got V": the words checkParameters() gives the command line, so a bad length reads
///        the same whichever stage refuses it.
inline void requirePositive(double value, const std::string& name)
{
    if (std::isfinite(value) && value > 0.0) return;
    std::ostringstream msg;
    msg << name << (std::isfinite(value) ? " must be > 0, got " : " must be finite, got ") << value;
    throw ParameterError(msg.str());
}

/// The largest r_e: the kernel squares lengths in single precision, so beyond it r_e²
/// overflows to +inf and every weight came out 0 or wrong without a word (a lattice scaled
/// by 1e20 kept 2.6% of its volume; rasterizeDensity() with r_e = 4e19 gave one particle's
/// voxels within reach density 0).
constexpr double kMaxEffectiveRadius = 1.0e18;

/// @throw ParameterError("--radius 4e+19 is too large: at most 1e+18 (lengths are squared
///        in single precision); give the positions in a larger unit", r_e named @a name)
///        if @a effectiveRadius exceeds kMaxEffectiveRadius: the one check of the parameter
///        estimate and of every stage that weighs by the kernel.
inline void requireRadiusBelowMaximum(double effectiveRadius, const std::string& name = "--radius")
{
    if (effectiveRadius <= kMaxEffectiveRadius) return;
    throw ParameterError(name + " " + number_text_internal::sixDigits(effectiveRadius) + " is too large: at most " +
                         number_text_internal::sixDigits(kMaxEffectiveRadius) +
                         " (lengths are squared in single precision); give the positions in a larger unit");
}

/// @throw ParameterError("<name> must lie in [0,1], got <value>") unless 0 <= @a value <= 1
/// (NaN refused): for --blend and --adaptivity, the value printed exactly where six digits
/// would show the limit (numberBeside()).
inline void requireUnitInterval(double value, const char* name)
{
    if (value >= 0.0 && value <= 1.0) return;
    throw ParameterError(std::string(name) + " must lie in [0,1], got " +
                         number_text_internal::numberBeside(value, value < 0.0 ? 0.0 : 1.0));
}

/// @throw ParameterError("volume offset must be Uniform or Convex, got 7") for a value that
///        is neither (an integer cast to VolumeOffset), which ran as Convex: the one check
///        of checkParameters() and preserveVolume().
inline void requireVolumeOffset(VolumeOffset offset)
{
    if (offset == VolumeOffset::Uniform || offset == VolumeOffset::Convex) return;
    throw ParameterError("volume offset must be Uniform or Convex, got " + std::to_string(int(offset)));
}

/// @a maxStep as the relaxation takes it: +inf, a natural way to say "no cap", is 0 (the
/// uncapped step); it was refused as "--max-step must be >= 0, got inf" (bug hunt).
/// @throw ParameterError("--max-step must be >= 0 (0 or inf: no cap), got -1" followed by
///        @a unit, e.g. " spacings") if it is negative or NaN.
inline double stepCap(double maxStep, const char* unit = "")
{
    if (maxStep == HUGE_VAL) return 0.0;
    if (maxStep >= 0.0) return maxStep;
    std::ostringstream msg;
    msg << "--max-step must be >= 0 (0 or inf: no cap), got " << maxStep << unit;
    throw ParameterError(msg.str());
}

} // namespace parameter_checks_internal
} // namespace nonbloppy
