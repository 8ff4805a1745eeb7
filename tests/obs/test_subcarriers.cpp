#include <gtest/gtest.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <algorithm>

using namespace mrpt_wifi;

TEST(Subcarriers, DataSubcarrierCountsAndExclusions)
{
    EXPECT_EQ(dataSubcarriers(80).size(), 234u);
    EXPECT_EQ(dataSubcarriers(40).size(), 108u);
    EXPECT_EQ(dataSubcarriers(20).size(), 52u);
    const auto has = [](unsigned bw, int k)
    {
        const auto& ks = dataSubcarriers(bw);
        return std::binary_search(ks.begin(), ks.end(), k);
    };
    for (int k : {0, 1, -1, 11, -11, 39, -39, 75, -75, 103, -103, 123, -123})
        EXPECT_FALSE(has(80, k)) << k;
    for (int k : {2, -2, 122, -122, 64, -64}) EXPECT_TRUE(has(80, k)) << k;
    for (int k : {0, 7, -21, 29}) EXPECT_FALSE(has(20, k)) << k;
    EXPECT_TRUE(has(20, 28));
    EXPECT_THROW(dataSubcarriers(320), std::invalid_argument);
}

TEST(Subcarriers, Vht160TwoSegmentsOfEighty)
{
    // Each 80 MHz segment keeps its own 234 data subcarriers, shifted by ∓128 (802.11ac).
    const auto& ks = dataSubcarriers(160);
    EXPECT_EQ(ks.size(), 468u);
    const auto& k80 = dataSubcarriers(80);
    for (int k : k80)
    {
        EXPECT_TRUE(std::binary_search(ks.begin(), ks.end(), k - 128)) << k;
        EXPECT_TRUE(std::binary_search(ks.begin(), ks.end(), k + 128)) << k;
    }
    for (int k : {0, 5, -5, 127, 128, 129, -128, 25, -231, 251, -251})
        EXPECT_FALSE(std::binary_search(ks.begin(), ks.end(), k)) << k;
    EXPECT_EQ(ks.front(), -250);
    EXPECT_EQ(ks.back(), 250);
}

TEST(Subcarriers, NegatedSubbandsPerEightyMhzSegment)
{
    EXPECT_TRUE(inNegatedSubband(-65, 80));
    EXPECT_FALSE(inNegatedSubband(-64, 80));
    EXPECT_FALSE(inNegatedSubband(-65, 40));
    // 160: the lowest 20 MHz of each 80 MHz segment (segment-local k < −64).
    EXPECT_TRUE(inNegatedSubband(-250, 160));
    EXPECT_TRUE(inNegatedSubband(-193, 160));
    EXPECT_FALSE(inNegatedSubband(-192, 160));
    EXPECT_FALSE(inNegatedSubband(-6, 160));
    EXPECT_TRUE(inNegatedSubband(6, 160));
    EXPECT_TRUE(inNegatedSubband(63, 160));
    EXPECT_FALSE(inNegatedSubband(64, 160));
}

TEST(Subcarriers, Intel5300Grouping)
{
    const auto& g20 = htGroupedSubcarriers(20);
    const auto& g40 = htGroupedSubcarriers(40);
    ASSERT_EQ(g20.size(), 30u);
    ASSERT_EQ(g40.size(), 30u);
    EXPECT_EQ(g20[13], -2);
    EXPECT_EQ(g20[14], -1);
    EXPECT_EQ(g20[15], 1);
    EXPECT_EQ(g20.back(), 28);
    EXPECT_EQ(g40.front(), -58);
    EXPECT_EQ(g40[15], 2);
    EXPECT_TRUE(std::is_sorted(g40.begin(), g40.end()));
    EXPECT_THROW(htGroupedSubcarriers(80), std::invalid_argument);
}

TEST(Subcarriers, BinMappingAndFrequencies)
{
    EXPECT_EQ(subcarrierToBin(-128, 256), 0u);
    EXPECT_EQ(subcarrierToBin(0, 256), 128u);
    EXPECT_EQ(binToSubcarrier(255, 256), 127);
    const auto cs = Chanspec::make(155, 80);
    EXPECT_DOUBLE_EQ(subcarrierFrequencyHz(cs, -122), 5775e6 - 122 * 312.5e3);
    EXPECT_EQ(firmwareOverwrittenSubcarriers(80), (std::vector<int>{0, 1, 2}));
    EXPECT_EQ(firmwareOverwrittenSubcarriers(20), (std::vector<int>{28, 29, 30}));
}
