// SPDX-License-Identifier: Apache-2.0
/// @file ExpNonPositive.h
/// @brief Private: e^x for x <= 0, the same bits from a scalar, an eight-lane AVX2 and a
///        sixteen-lane AVX-512F copy, for the smoothing's normal filter. Only src/ and the
///        tests include it.
///
/// e^x from IEEE additions, multiplications and integer bit operations alone (Cephes' expf:
/// x = k ln 2 + r, |r| ≤ ln 2 / 2, a degree-7 polynomial for e^r, then 2^k into the exponent),
/// in a scalar copy and eight- and sixteen-lane copies that do the same operations lane by
/// lane, so all give the same bits (tests/test_InstructionSet.cc), within 1 ulp of e^x
/// (tests/test_SmoothSurface.cc). glibc's expf, a table lookup per call that no loop can
/// vectorize, took most of the smoothing's normal rounds.

#ifndef NONBLOPPY_EXP_NON_POSITIVE_H
#define NONBLOPPY_EXP_NON_POSITIVE_H

#include "InstructionSet.h"

#include <cstdint>
#include <cstring>

#if NONBLOPPY_HAS_AVX2_COPY
#include <immintrin.h>
#endif

namespace nonbloppy {
namespace exp_internal {

/// Below this e^x is under float's smallest normal number: the result is +0.
constexpr float kExpLowest = -87.33654f;
constexpr float kLog2e = 1.44269504088896341f;
/// 1.5·2^23: adding it rounds a float of magnitude < 2^22 to an integer (to nearest, even on
/// ties), which then sits in the low bits of the sum.
constexpr float kRoundToInteger = 12582912.0f;
constexpr float kLn2High = 0.693359375f;      // ln 2 in few bits: k·kLn2High is exact
constexpr float kLn2Low = -2.12194440e-4f;    // ln 2 − kLn2High
constexpr float kExpP0 = 1.9875691500e-4f, kExpP1 = 1.3981999507e-3f, kExpP2 = 8.3334519073e-3f,
                kExpP3 = 4.1665795894e-2f, kExpP4 = 1.6666665459e-1f, kExpP5 = 5.0000001201e-1f;

/// e^x for x ≤ 0 (and NaN, which it returns); +0 below kExpLowest. Positive x are outside
/// what it is tested for: the normal filter's arguments, −|n_i − n_j|²/2σ_r², never are.
inline float expNonPositive(float x)
{
    const float clamped = kExpLowest > x ? kExpLowest : x;
    const float shifted = clamped * kLog2e + kRoundToInteger;
    const float k = shifted - kRoundToInteger;
    float r = clamped - k * kLn2High;
    r = r - k * kLn2Low;
    float p = kExpP0;
    p = p * r + kExpP1;
    p = p * r + kExpP2;
    p = p * r + kExpP3;
    p = p * r + kExpP4;
    p = p * r + kExpP5;
    const float y = (p * (r * r) + r) + 1.0f;
    uint32_t shiftedBits, roundBits;
    std::memcpy(&shiftedBits, &shifted, sizeof(float));
    const float round = kRoundToInteger;
    std::memcpy(&roundBits, &round, sizeof(float));
    const uint32_t scaleBits = (shiftedBits - roundBits + 127u) << 23;  // 2^k, k in [−126, 0]
    float scale;
    std::memcpy(&scale, &scaleBits, sizeof(float));
    return x < kExpLowest ? 0.0f : y * scale;
}

#if NONBLOPPY_HAS_AVX2_COPY
/// expNonPositive() on eight lanes.
NONBLOPPY_TARGET_AVX2 inline __m256 expNonPositiveAvx2(__m256 x)
{
    const __m256 lowest = _mm256_set1_ps(kExpLowest), roundToInteger = _mm256_set1_ps(kRoundToInteger);
    const __m256 clamped = _mm256_max_ps(lowest, x);  // lowest > x ? lowest : x, NaN kept
    const __m256 shifted = _mm256_add_ps(_mm256_mul_ps(clamped, _mm256_set1_ps(kLog2e)), roundToInteger);
    const __m256 k = _mm256_sub_ps(shifted, roundToInteger);
    __m256 r = _mm256_sub_ps(clamped, _mm256_mul_ps(k, _mm256_set1_ps(kLn2High)));
    r = _mm256_sub_ps(r, _mm256_mul_ps(k, _mm256_set1_ps(kLn2Low)));
    __m256 p = _mm256_set1_ps(kExpP0);
    p = _mm256_add_ps(_mm256_mul_ps(p, r), _mm256_set1_ps(kExpP1));
    p = _mm256_add_ps(_mm256_mul_ps(p, r), _mm256_set1_ps(kExpP2));
    p = _mm256_add_ps(_mm256_mul_ps(p, r), _mm256_set1_ps(kExpP3));
    p = _mm256_add_ps(_mm256_mul_ps(p, r), _mm256_set1_ps(kExpP4));
    p = _mm256_add_ps(_mm256_mul_ps(p, r), _mm256_set1_ps(kExpP5));
    const __m256 y = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(p, _mm256_mul_ps(r, r)), r), _mm256_set1_ps(1.0f));
    const __m256i scaleBits = _mm256_slli_epi32(
        _mm256_add_epi32(_mm256_sub_epi32(_mm256_castps_si256(shifted), _mm256_castps_si256(roundToInteger)),
                         _mm256_set1_epi32(127)),
        23);
    const __m256 underflow = _mm256_cmp_ps(x, lowest, _CMP_LT_OQ);
    return _mm256_andnot_ps(underflow, _mm256_mul_ps(y, _mm256_castsi256_ps(scaleBits)));
}

/// expNonPositive() on sixteen lanes (AVX-512F). The full-mask maskz forms of max, shift and
/// (in the caller) square root are the plain instructions: GCC 12's plain intrinsics merge
/// into an uninitialized register and warn (-Wmaybe-uninitialized).
NONBLOPPY_TARGET_AVX512 inline __m512 expNonPositiveAvx512(__m512 x)
{
    const __mmask16 all = 0xFFFF;
    const __m512 lowest = _mm512_set1_ps(kExpLowest), roundToInteger = _mm512_set1_ps(kRoundToInteger);
    const __m512 clamped = _mm512_maskz_max_ps(all, lowest, x);  // lowest > x ? lowest : x, NaN kept
    const __m512 shifted = _mm512_add_ps(_mm512_mul_ps(clamped, _mm512_set1_ps(kLog2e)), roundToInteger);
    const __m512 k = _mm512_sub_ps(shifted, roundToInteger);
    __m512 r = _mm512_sub_ps(clamped, _mm512_mul_ps(k, _mm512_set1_ps(kLn2High)));
    r = _mm512_sub_ps(r, _mm512_mul_ps(k, _mm512_set1_ps(kLn2Low)));
    __m512 p = _mm512_set1_ps(kExpP0);
    p = _mm512_add_ps(_mm512_mul_ps(p, r), _mm512_set1_ps(kExpP1));
    p = _mm512_add_ps(_mm512_mul_ps(p, r), _mm512_set1_ps(kExpP2));
    p = _mm512_add_ps(_mm512_mul_ps(p, r), _mm512_set1_ps(kExpP3));
    p = _mm512_add_ps(_mm512_mul_ps(p, r), _mm512_set1_ps(kExpP4));
    p = _mm512_add_ps(_mm512_mul_ps(p, r), _mm512_set1_ps(kExpP5));
    const __m512 y = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(p, _mm512_mul_ps(r, r)), r), _mm512_set1_ps(1.0f));
    const __m512i scaleBits = _mm512_maskz_slli_epi32(
        all,
        _mm512_add_epi32(_mm512_sub_epi32(_mm512_castps_si512(shifted), _mm512_castps_si512(roundToInteger)),
                         _mm512_set1_epi32(127)),
        23);
    const __mmask16 underflow = _mm512_cmp_ps_mask(x, lowest, _CMP_LT_OQ);
    return _mm512_maskz_mov_ps(__mmask16(~underflow), _mm512_mul_ps(y, _mm512_castsi512_ps(scaleBits)));
}
#endif

} // namespace exp_internal
} // namespace nonbloppy

#endif // NONBLOPPY_EXP_NON_POSITIVE_H
