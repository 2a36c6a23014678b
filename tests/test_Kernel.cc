// SPDX-License-Identifier: Apache-2.0
#include <nonbloppy/Kernel.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace nonbloppy;

TEST(Kernel, ValuesInsideTheSupport)
{
    EXPECT_FLOAT_EQ(mpsWeight(0.5f, 1.0f), 1.0f);   // r_e/d − 1 = 2 − 1
    EXPECT_FLOAT_EQ(mpsWeight(0.25f, 2.0f), 7.0f);  // 8 − 1
    EXPECT_FLOAT_EQ(mpsWeight(0.9f, 1.0f), 1.0f / 0.9f - 1.0f);
}

TEST(Kernel, ZeroAtAndBeyondTheEffectiveRadius)
{
    EXPECT_EQ(mpsWeight(1.0f, 1.0f), 0.0f);
    EXPECT_EQ(mpsWeight(1.5f, 1.0f), 0.0f);
    EXPECT_EQ(mpsWeightSquared(1.0f, 1.0f), 0.0f);
    EXPECT_EQ(mpsWeightSquared(4.0f, 1.0f), 0.0f);
}

TEST(Kernel, ClampKeepsTheSingularityFinite)
{
    const float atZero = mpsWeight(0.0f, 1.0f);
    EXPECT_TRUE(std::isfinite(atZero));
    EXPECT_FLOAT_EQ(atZero, 1.0f / kMinDistanceFraction - 1.0f);
    EXPECT_FLOAT_EQ(mpsWeight(1e-6f, 0.1f), atZero);  // clamp is relative to r_e
    EXPECT_FLOAT_EQ(mpsWeightSquared(0.0f, 0.1f), atZero);
}

TEST(Kernel, SquaredFormAgreesWithDistanceForm)
{
    for (float d = 0.01f; d < 1.2f; d += 0.01f) {
        EXPECT_NEAR(mpsWeightSquared(d * d, 1.0f), mpsWeight(d, 1.0f), 1e-4f * (1.0f + mpsWeight(d, 1.0f)));
    }
}
