// makecsiparams: the exact 34-byte struct (bytes written out by hand), its base64, errors.
#include <gtest/gtest.h>
#include <mrpt_wifi/emulator/CsiParams.h>

#include <array>

using namespace mrpt_wifi;
using namespace mrpt_wifi::emulator;

namespace
{
std::vector<uint8_t> decoded(const ToolResult& r)
{
    std::string text = r.out;
    while (!text.empty() && text.back() == '\n') text.pop_back();
    const auto bytes = base64Decode(text);
    return bytes ? *bytes : std::vector<uint8_t>{};
}
}  // namespace

TEST(EmulatorCsiParams, WirosStyleArgumentsGiveTheExactStruct)
{
    const auto r = makeCsiParams(
        {"-e", "1", "-c", "155/80", "-C", "0xf", "-N", "0xf", "-m", "11:22:33:44:55:66", "-d",
         "0x50"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    // chanspec 0xe09b LE, collect, core|nss<<4, no packet filter, 1 MAC, MAC, 3 empty MACs,
    // delay 0x50 LE.
    const std::vector<uint8_t> expected = {0x9b, 0xe0, 0x01, 0xff, 0x00, 0x00, 0x01, 0x00, 0x11,
                                           0x22, 0x33, 0x44, 0x55, 0x66, 0,    0,    0,    0,
                                           0,    0,    0,    0,    0,    0,    0,    0,    0,
                                           0,    0,    0,    0,    0,    0x50, 0x00};
    EXPECT_EQ(decoded(r), expected);
    // The text nexutil gets (computed independently with Python's base64 module).
    EXPECT_EQ(r.out, "m+AB/wAAAQARIjNEVWYAAAAAAAAAAAAAAAAAAAAAAABQAA==\n");
}

TEST(EmulatorCsiParams, MasksPacketFilterAndSeveralMacs)
{
    const auto r = makeCsiParams(
        {"-c", "42/80", "-C", "0x5", "-N", "1", "-b", "0x88", "-m",
         "02:aa:00:00:00:01,02:CC:0:0:0:3"});
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.out, "KuABFQGIAgACqgAAAAECzAAAAAMAAAAAAAAAAAAAAAAAAA==\n");
    const auto bytes = decoded(r);
    ASSERT_EQ(bytes.size(), kCsiParamsBytes);
    const CsiParams p = CsiParams::fromBytes(bytes.data(), bytes.size());
    EXPECT_TRUE(p.collect);  // -e defaults to 1
    EXPECT_EQ(p.chanspec()->asString(), "42/80");
    EXPECT_EQ(p.coreMask, 0x5);
    EXPECT_EQ(p.nssMask, 0x1);
    EXPECT_TRUE(p.usePacketFilter);
    EXPECT_EQ(p.firstPacketByte, 0x88);
    ASSERT_EQ(p.macFilter.size(), 2u);
    EXPECT_EQ(p.macFilter[1].asString(), "02:cc:00:00:00:03");
    EXPECT_EQ(p.delay_us, 0);  // 2 pairs: no automatic delay
}

TEST(EmulatorCsiParams, AutomaticDelayForTwelveOrMorePairsAndDisable)
{
    auto p = csiParamsFromArguments({"-c", "155/80", "-C", "0xf", "-N", "0x7"});  // 12 pairs
    EXPECT_EQ(p.delay_us, kDefaultBusyDelay_us);
    p = csiParamsFromArguments({"-c", "155/80", "-C", "0xf", "-N", "0x3"});  // 8 pairs
    EXPECT_EQ(p.delay_us, 0);
    // -e 0 needs neither channel nor masks: all zero.
    const auto off = makeCsiParams({"-e", "0"});
    ASSERT_EQ(off.exitCode, 0) << off.err;
    EXPECT_EQ(off.out, "AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA==\n");
    // Raw output: the 34 bytes themselves; hex chanspec words as UbiLocate's scripts pass them.
    const auto raw = makeCsiParams({"-r", "-c", "0xe09b", "-C", "1", "-N", "1"});
    ASSERT_EQ(raw.exitCode, 0);
    ASSERT_EQ(raw.out.size(), kCsiParamsBytes);
    EXPECT_EQ(uint8_t(raw.out[0]), 0x9b);
    EXPECT_EQ(uint8_t(raw.out[1]), 0xe0);
}

TEST(EmulatorCsiParams, BadArgumentsExitNonZeroWithTheToolsMessage)
{
    const std::vector<std::pair<Argv, std::string>> cases = {
        {{"-e", "1", "-C", "0xf", "-N", "0xf"}, "No channel given"},
        {{"-c", "155/80", "-C", "0xf"}, "No nssmask and/or coremask given"},
        {{"-c", "155/80", "-C", "0x1f", "-N", "1"}, "Invalid core mask"},
        {{"-c", "155/80", "-C", "1", "-N", "0x10"}, "Invalid nss mask"},
        {{"-c", "999/80", "-C", "1", "-N", "1"}, "Invalid chanspec"},
        {{"-c", "155/80", "-C", "1", "-N", "1", "-m", "11:22:33"}, "Invalid mac address"},
        {{"-c", "155/80", "-C", "1", "-N", "1", "-m",
          "1:2:3:4:5:6,1:2:3:4:5:7,1:2:3:4:5:8,"
          "1:2:3:4:5:9,1:2:3:4:5:a"},
         "Only 4 mac addresses"},
        {{"-c", "155/80", "-C", "1", "-N", "1", "-b", "256"}, "Invalid byte filter"},
        {{"-c", "155/80", "-C", "1", "-N", "1", "-d", "-3"}, "Invalid delay"},
        {{"-x"}, "Invalid option"},
        {{"-c"}, "Invalid option"}};
    for (const auto& [args, message] : cases)
    {
        const auto r = makeCsiParams(args);
        EXPECT_NE(r.exitCode, 0) << args[0];
        EXPECT_TRUE(r.out.empty());
        EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    }
    EXPECT_EQ(makeCsiParams({"-h"}).exitCode, 0);
}

TEST(EmulatorCsiParams, Base64RoundTripAndStrictDecoding)
{
    for (size_t n = 0; n < 40; ++n)
    {
        std::vector<uint8_t> data(n);
        for (size_t i = 0; i < n; ++i) data[i] = uint8_t(i * 37 + 11);
        const auto back = base64Decode(base64Encode(data.data(), data.size()));
        ASSERT_TRUE(back);
        EXPECT_EQ(*back, data);
    }
    EXPECT_EQ(base64Encode(reinterpret_cast<const uint8_t*>("Ma"), 2), "TWE=");
    for (const char* bad : {"abc", "ab=c", "####", "a===", "TWE=TWE=", "TW E"})
        EXPECT_FALSE(base64Decode(bad)) << bad;
}

TEST(EmulatorCsiParams, HardwareMacFilterComparesOnlyTheFirstTwoBytes)
{
    CsiParams p;
    EXPECT_TRUE(p.hardwareMacFilterPasses(MacAddress::fromString("de:ad:be:ef:00:01")));
    p.macFilter = {MacAddress::fromString("11:22:33:44:55:66")};
    EXPECT_TRUE(p.hardwareMacFilterPasses(MacAddress::fromString("11:22:33:44:55:66")));
    EXPECT_TRUE(p.hardwareMacFilterPasses(MacAddress::fromString("11:22:99:99:99:99")));
    EXPECT_FALSE(p.hardwareMacFilterPasses(MacAddress::fromString("11:23:33:44:55:66")));
    EXPECT_FALSE(p.hardwareMacFilterPasses(MacAddress::fromString("12:22:33:44:55:66")));
}

TEST(EmulatorCsiParams, FromBytesRejectsWhatTheFirmwareRejects)
{
    std::array<uint8_t, kCsiParamsBytes> b{};
    EXPECT_THROW(CsiParams::fromBytes(b.data(), 33), std::invalid_argument);
    b[6] = 5;  // n_mac_addr > 4
    EXPECT_THROW(CsiParams::fromBytes(b.data(), b.size()), std::invalid_argument);
}
