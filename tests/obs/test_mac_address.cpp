#include <gtest/gtest.h>
#include <mrpt_wifi/obs/MacAddress.h>

using mrpt_wifi::MacAddress;
using mrpt_wifi::MacPattern;

TEST(MacAddress, ParsesAndPrintsLowercase)
{
    const auto m = MacAddress::fromString("00:12:34:56:78:9B");
    EXPECT_EQ(m.asString(), "00:12:34:56:78:9b");
    EXPECT_EQ(m.asUint64(), 0x00123456789bull);
    EXPECT_EQ(MacAddress::fromString("00-12-34-56-78-9b"), m);
    for (const char* bad :
         {"", "00:12:34:56:78", "00:12:34:56:78:9b:00", "0:12:34:56:78:9b", "00:12:34:56:78:9g",
          "00:12:34:56:78:*"})
        EXPECT_FALSE(MacAddress::parse(bad)) << bad;
    EXPECT_THROW(MacAddress::fromString("nope"), std::invalid_argument);
}

TEST(MacPattern, MatchesWithWildcards)
{
    const auto p = MacPattern::fromString("11:11:11:*:*:*");
    EXPECT_TRUE(p.matches(MacAddress::fromString("11:11:11:00:ab:cd")));
    EXPECT_FALSE(p.matches(MacAddress::fromString("11:11:12:00:ab:cd")));
    EXPECT_EQ(p.asString(), "11:11:11:*:*:*");
    EXPECT_TRUE(MacPattern::fromString("*:*:*:*:*:*").matches(MacAddress{}));
    const auto exact = MacPattern::fromString("00:12:34:56:78:9b");
    EXPECT_TRUE(exact.matches(MacAddress::fromString("00:12:34:56:78:9b")));
    EXPECT_FALSE(exact.matches(MacAddress::fromString("00:12:34:56:78:9c")));
    EXPECT_THROW(MacPattern::fromString("11:11:11:**:00:00"), std::invalid_argument);
}
