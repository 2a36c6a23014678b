// SPDX-License-Identifier: Apache-2.0
/// @file InstructionSet.h
/// @brief Private: the vector instructions a hot loop is compiled for, chosen at run time.
///        Only src/ and the tests include it.
///
/// The library is built for the x86-64 baseline (SSE2), as Debian builds it. The inner
/// loops of the rasterization, the relaxation and the smoothing's normal rounds also have a
/// copy compiled for AVX2 (eight lanes in one register instead of two), taken when the CPU
/// has AVX2, and the normal rounds a third for AVX-512F (sixteen lanes), taken when it has
/// that: their exponentials are multiplies and adds, which AVX-512 does twice as many of per
/// instruction, while the rasterization and the relaxation wait on the divider, which it
/// does not speed up. Every copy gives the same bits, which keeps meshes identical across
/// machines: each lane does the same IEEE additions, multiplications, divisions and square
/// roots (and the smoothing's integer exponent arithmetic) in the same order, and no copy
/// fuses a multiply-add (the library is compiled with -ffp-contract=off).
/// tests/test_InstructionSet.cc compares them on a real frame.

#ifndef NONBLOPPY_INSTRUCTION_SET_H
#define NONBLOPPY_INSTRUCTION_SET_H

#include <nonbloppy/Mesh.h>
#include <nonbloppy/ParticleIndex.h>
#include <nonbloppy/RasterizeDensity.h>
#include <nonbloppy/RelaxVertices.h>
#include <nonbloppy/SmoothSurface.h>

#include <openvdb/util/NullInterrupter.h>

/// Marks a function to be compiled for AVX2 as well as the baseline (x86-64 with GCC or
/// clang); elsewhere the AVX2 copy is the baseline one.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define NONBLOPPY_HAS_AVX2_COPY 1
#define NONBLOPPY_TARGET_AVX2 __attribute__((target("avx2")))
#define NONBLOPPY_TARGET_AVX512 __attribute__((target("avx512f")))
#else
#define NONBLOPPY_HAS_AVX2_COPY 0
#define NONBLOPPY_TARGET_AVX2
#define NONBLOPPY_TARGET_AVX512
#endif

namespace nonbloppy {
namespace instruction_set_internal {

/// Which copy of a hot loop runs.
enum class InstructionSet
{
    Auto,      ///< the widest copy the CPU can run: AVX-512F, AVX2, else the baseline
    Avx2,      ///< the AVX2 copy where the CPU has AVX2 (also where it has AVX-512), else the baseline
    Baseline,  ///< the x86-64 baseline (SSE2) copy, whatever the CPU
};

/// Whether the AVX2 copy runs for @a set. Cost: a CPUID lookup cached by the compiler's
/// runtime (__builtin_cpu_supports).
inline bool useAvx2(InstructionSet set)
{
#if NONBLOPPY_HAS_AVX2_COPY
    return set != InstructionSet::Baseline && __builtin_cpu_supports("avx2");
#else
    (void)set;
    return false;
#endif
}

/// Whether a loop's AVX-512F copy, where it has one, runs for @a set. Cost: as useAvx2().
inline bool useAvx512(InstructionSet set)
{
#if NONBLOPPY_HAS_AVX2_COPY
    return set == InstructionSet::Auto && __builtin_cpu_supports("avx512f");
#else
    (void)set;
    return false;
#endif
}

/// rasterizeDensity() running the copy of its inner loop that @a set picks (the public
/// function passes Auto). Same checks, throws and thread-safety.
openvdb::FloatGrid::Ptr rasterizeDensity(const ParticleIndex& particles, const DensitySettings& settings,
                                         openvdb::util::NullInterrupter* interrupter, InstructionSet set);

/// relaxVertices() running the copy of its inner loop that @a set picks (the public
/// function passes Auto). Same checks, throws and thread-safety.
void relaxVertices(SurfaceMesh& mesh, const ParticleIndex& particles, const RelaxSettings& settings,
                   openvdb::util::NullInterrupter* interrupter, InstructionSet set);

/// smoothSurface() running the copy of its normal rounds' loop that @a set picks (the
/// public function passes Auto). Same checks, throws and thread-safety.
void smoothSurface(SurfaceMesh& mesh, const SmoothSettings& settings, openvdb::util::NullInterrupter* interrupter,
                   InstructionSet set);

} // namespace instruction_set_internal
} // namespace nonbloppy

#endif // NONBLOPPY_INSTRUCTION_SET_H
