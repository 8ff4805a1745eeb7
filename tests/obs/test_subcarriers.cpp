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
    EXPECT_THROW(dataSubcarriers(160), std::invalid_argument);
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
