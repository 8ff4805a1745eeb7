#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>

#include "SensorConfigError.h"

using namespace mrpt_wifi;

TEST(CWiFiCSISensorConfig, RegisteredForRawlogGrabber)
{
    auto sensor = mrpt::hwdrivers::CGenericSensor::createSensorPtr("CWiFiCSISensor");
    ASSERT_TRUE(sensor);
    EXPECT_NE(dynamic_cast<CWiFiCSISensor*>(sensor.get()), nullptr);
}

TEST(CWiFiCSISensorConfig, ValidConfigurationLoads)
{
    EXPECT_EQ(
        test::sensorConfigError(
            "[CSI]\ndriver = CWiFiCSISensor\nprocess_rate = 100\nsensorLabel = CSI_FRONT\n"
            "udp_port = 5600\nmac_filter = 11:11:11:*:*:*, 00:12:34:56:78:9b\n"
            "pose_yaw = 90\nchannel = 157/80\nrouter_control = true\nlogin_host = 127.0.0.1\n"
            "scan_period = 20\nauto_channel = true\ncore_mask = 0x3\n"),
        "");
}

TEST(CWiFiCSISensorConfig, WrongKeysAndValuesAreNamed)
{
    // A typo: named, with its section and the key it probably meant.
    auto e = test::sensorConfigError(
        "[CSI]\ndriver = CWiFiCSISensor\nprocess_rate = 100\nudp_prot = 5500\n");
    EXPECT_NE(e.find("section 'CSI': unknown key 'udp_prot'"), std::string::npos) << e;
    EXPECT_NE(e.find("did you mean 'udp_port'"), std::string::npos) << e;

    e = test::sensorConfigError("[CSI]\nprocess_rate = 100\nudp_port = 70000\n");
    EXPECT_NE(e.find("udp_port"), std::string::npos) << e;
    e = test::sensorConfigError("[CSI]\nprocess_rate = 100\nchannel = 155/160\n");
    EXPECT_NE(e.find("155/160"), std::string::npos) << e;
    e = test::sensorConfigError("[CSI]\nprocess_rate = 100\nmac_filter = 11:11:1x:*:*:*\n");
    EXPECT_NE(e.find("11:11:1x"), std::string::npos) << e;
    e = test::sensorConfigError("[CSI]\nprocess_rate = 100\nscanner = radar\n");
    EXPECT_NE(e.find("'scanner'"), std::string::npos) << e;
    // The host's own card may scan without router control; router scans may not.
    EXPECT_EQ(
        test::sensorConfigError("[CSI]\nprocess_rate = 100\nscan_period = 10\nscanner = host\n"),
        "");
    e = test::sensorConfigError("[CSI]\nprocess_rate = 100\nscan_period = 10\n");
    EXPECT_NE(e.find("router_control"), std::string::npos) << e;
    e = test::sensorConfigError("[CSI]\nprocess_rate = 100\nsource = serial\n");
    EXPECT_NE(e.find("'source'"), std::string::npos) << e;
    e = test::sensorConfigError("[CSI]\nprocess_rate = 100\nsource = pcap\n");
    EXPECT_NE(e.find("pcap_file"), std::string::npos) << e;
    e = test::sensorConfigError("[CSI]\nprocess_rate = 100\nauto_channel = true\n");
    EXPECT_NE(e.find("router_control"), std::string::npos) << e;
    e = test::sensorConfigError(
        "[CSI]\nprocess_rate = 100\npacket_mac_filter = "
        "02:00:00:00:00:01,02:00:00:00:00:02,02:00:00:00:00:03,02:00:00:00:00:04,02:00:00:00:00:"
        "05\n");
    EXPECT_NE(e.find("at most 4"), std::string::npos) << e;
}

TEST(CWiFiCSISensorConfig, ValuesForTheRouterShellAreValidated)
{
    // A typo that would be a second command in the router's shell is an error naming the key.
    for (const char* key :
         {"setup_interface_5g", "setup_interface_2g4", "setup_bridge", "setup_module_path"})
        for (const char* value :
             {"eth6; reboot", "eth6 && reboot", "$(reboot)", "`reboot`", "eth6|reboot", "a b",
              "x'y", "eth6>/jffs/x"})
        {
            const auto e = test::sensorConfigError(
                std::string("[CSI]\nprocess_rate = 100\nrouter_control = true\n") + key + " = " +
                value + "\n");
            EXPECT_NE(e.find(std::string("key '") + key + "'"), std::string::npos)
                << key << " = " << value << ": " << e;
        }
    EXPECT_EQ(
        test::sensorConfigError(
            "[CSI]\nprocess_rate = 100\nsetup_interface_5g = wl0.1\nsetup_bridge = br-lan\n"
            "setup_module_path = /jffs/nexmon/dhd_v2.ko\n"),
        "");
}

TEST(CWiFiCSISensorConfig, ChannelScheduleAndItsConflicts)
{
    const std::string base = "[CSI]\nprocess_rate = 100\nrouter_control = true\n";
    EXPECT_EQ(
        test::sensorConfigError(
            base + "channel_schedule = 36/80 149/80 6/20\nchannel_dwell_s = 1.5\n"),
        "");
    EXPECT_EQ(test::sensorConfigError(base + "channel_schedule = scan\nscan_period = 10\n"), "");
    // Both hopping and following the strongest AP: which one decides is named.
    auto e = test::sensorConfigError(
        base + "channel_schedule = 42/80 155/80\nauto_channel = true\nscan_period = 10\n");
    EXPECT_NE(e.find("channel_schedule and auto_channel"), std::string::npos) << e;
    e = test::sensorConfigError("[CSI]\nprocess_rate = 100\nchannel_schedule = 42/80 155/80\n");
    EXPECT_NE(e.find("channel_schedule needs router_control"), std::string::npos) << e;
    e = test::sensorConfigError(base + "channel_schedule = scan\n");
    EXPECT_NE(e.find("scan_period"), std::string::npos) << e;
    e = test::sensorConfigError(base + "channel_schedule = 42/80 15x/80\n");
    EXPECT_NE(e.find("'15x/80'"), std::string::npos) << e;
    e = test::sensorConfigError(base + "channel_schedule = 42/80 36/80\n");  // the same channel
    EXPECT_NE(e.find("listed twice"), std::string::npos) << e;
    e = test::sensorConfigError(base + "channel_schedule = 42/80 155/80\nchannel_dwell_s = 0\n");
    EXPECT_NE(e.find("channel_dwell_s"), std::string::npos) << e;
    e = test::sensorConfigError(base + "channel_dwell_s = 3\n");
    EXPECT_NE(e.find("channel_dwell_s' needs channel_schedule"), std::string::npos) << e;
    e = test::sensorConfigError(
        base + "channel_schedule = 42/80 155/80\ntransmitter_mode = true\n");
    EXPECT_NE(e.find("transmitter_mode"), std::string::npos) << e;
}
