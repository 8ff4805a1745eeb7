#include <gtest/gtest.h>
#include <mrpt_wifi/sensor/NexmonRouterControl.h>

#include <filesystem>
#include <fstream>

using namespace mrpt_wifi;

TEST(ScanParsers, WlScanResults)
{
    const std::string text =
        "SSID: \"lab-ap\"\n"
        "Mode: Managed\tRSSI: -47 dBm\tSNR: 46 dB\tnoise: -93 dBm\tFlags: RSSI on-channel "
        "\tChannel: 157/80\n"
        "BSSID: A0:04:60:12:34:56\tCapability: ESS ShortSlot RRM \n"
        "Supported Rates: [ 6(b) 9 12(b) 18 24(b) 36 48 54 ]\n"
        "VHT Capable:\n"
        "\tChanspec: 5GHz channel 155 80MHz (0xe29b)\n\n"
        "SSID: \"\"\n"
        "Mode: Managed\tRSSI: -80 dBm\tSNR: 10 dB\tnoise: -92 dBm\tChannel: 36\n"
        "BSSID: 02:00:00:00:00:01\tCapability: ESS\n\n"
        "SSID: \"broken\"\n"
        "Mode: Managed\tRSSI: -60 dBm\n";  // no BSSID: dropped
    const auto aps = parseWlScanResults(text);
    ASSERT_EQ(aps.size(), 2u);
    EXPECT_EQ(aps[0].ssid, "lab-ap");
    EXPECT_EQ(aps[0].bssid.asString(), "a0:04:60:12:34:56");
    EXPECT_EQ(aps[0].rssi_dBm, -47);
    EXPECT_EQ(aps[0].noise_dBm, -93);
    EXPECT_EQ(aps[0].chanspec.raw, 0xe29b);
    EXPECT_EQ(aps[1].ssid, "");
    EXPECT_EQ(aps[1].chanspec.centerChannel, 36);
    EXPECT_EQ(aps[1].chanspec.bandwidthMHz, 20);
}

TEST(ScanParsers, IwScan)
{
    const std::string text =
        "BSS a0:04:60:12:34:56(on wlan0)\n"
        "\tfreq: 5785\n"
        "\tsignal: -47.00 dBm\n"
        "\tSSID: lab-ap\n"
        "\tHT operation:\n"
        "\t\t * primary channel: 157\n"
        "\t\t * secondary channel offset: above\n"
        "\tVHT operation:\n"
        "\t\t * channel width: 1 (80 MHz)\n"
        "\t\t * center freq segment 1: 155\n"
        "BSS 02:00:00:00:00:02(on wlan0)\n"
        "\tfreq: 2437\n"
        "\tsignal: -61.50 dBm\n"
        "\tSSID: old\n";
    const auto aps = parseIwScan(text);
    ASSERT_EQ(aps.size(), 2u);
    EXPECT_EQ(aps[0].chanspec.centerChannel, 155);
    EXPECT_EQ(aps[0].chanspec.bandwidthMHz, 80);
    EXPECT_EQ(aps[0].chanspec.controlChannel(), 157u);
    EXPECT_EQ(aps[0].rssi_dBm, -47);
    EXPECT_EQ(aps[1].chanspec.centerChannel, 6);
    EXPECT_EQ(aps[1].chanspec.band, WifiBand::Band2G4);
    EXPECT_EQ(aps[1].rssi_dBm, -62);
}

TEST(ScanParsers, HostScanRunsIwAndReportsItsFailure)
{
    // A stand-in `iw` first in PATH: the real one needs a WiFi card and CAP_NET_ADMIN.
    const std::string dir = ::testing::TempDir() + "/fake_iw";
    std::filesystem::create_directories(dir);
    {
        std::ofstream iw(dir + "/iw");
        iw << "#!/bin/sh\n"
              "if [ \"$2\" = wlan9 ]; then echo 'command failed: No such device (-19)' >&2; exit "
              "237; fi\n"
              "printf 'BSS a0:04:60:12:34:56(on %s)\\n\\tfreq: 5785\\n\\tsignal: -47.00 "
              "dBm\\n\\tSSID: lab\\n"
              "\\tVHT operation:\\n\\t\\t * channel width: 1 (80 MHz)\\n\\t\\t * center freq "
              "segment 1: 155\\n"
              "\\tHT operation:\\n\\t\\t * primary channel: 157\\n' \"$2\"\n";
    }
    std::filesystem::permissions(dir + "/iw", std::filesystem::perms::owner_all);
    const std::string oldPath = std::getenv("PATH");
    ::setenv("PATH", (dir + ":" + oldPath).c_str(), 1);
    const auto aps = scanWithHostInterface("wlan0", 5);
    ASSERT_EQ(aps.size(), 1u);
    EXPECT_EQ(aps[0].chanspec.raw, Chanspec::fromString("157/80").raw);
    EXPECT_EQ(aps[0].rssi_dBm, -47);
    try
    {
        scanWithHostInterface("wlan9", 5);
        ADD_FAILURE() << "a failing iw must be an error";
    }
    catch (const RouterError& e)
    {
        EXPECT_NE(std::string(e.what()).find("No such device"), std::string::npos) << e.what();
    }
    ::setenv("PATH", oldPath.c_str(), 1);
}
