/* mrpt_wifi — WiFi channel state information for MRPT.  */
// Issue 20.4: WiROS's bags in and out. The messages' wire format and MD5s here; the bags
// through Debian's python3-rosbag (ROS's own reader and writer) and rostopic.
#include <gtest/gtest.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/RosMessages.h>

#include <filesystem>

#include "SyntheticCsi.h"
#include "TestSupport.h"

using namespace mrpt_wifi;

TEST(RosMessages, Md5sAreRos1s)
{
    // ROS 1's published MD5 of std_msgs/Header (its definition without comments).
    EXPECT_EQ(
        ros1::messageMd5("uint32 seq\ntime stamp # a comment\n\nstring frame_id\n", {}),
        "2176decaecbce78abc3b96ef049fabed");
    EXPECT_EQ(ros1::wifiType().datatype, "rf_msgs/Wifi");
    EXPECT_EQ(ros1::bearingType().datatype, "rf_msgs/Bearing");
    EXPECT_NE(ros1::wifiType().definition.find("MSG: std_msgs/Header"), std::string::npos);
}

TEST(RosMessages, WifiRoundTripAndBadBytesAreNamed)
{
    const auto frame = test::syntheticFrame(4, 4, 80, 7);
    frame->setPresent(3, 2, false);
    for (unsigned b = 0; b < frame->nfft(); ++b) frame->at(3, 2, b) = {0, 0};
    const auto msg = ros1::fromObservation(*frame, "rx-a");
    EXPECT_EQ(msg.nSub, 256u);
    EXPECT_EQ(msg.csiReal.size(), 256u * 16u);
    const auto bytes = ros1::serialize(msg);
    ros1::WifiMessage back;
    std::string why;
    ASSERT_TRUE(ros1::deserialize(bytes.data(), bytes.size(), back, why)) << why;
    CObservationWiFiCSI obs;
    ASSERT_TRUE(ros1::toObservation(back, obs, why)) << why;
    EXPECT_EQ(obs.csi, frame->csi);
    EXPECT_EQ(obs.presentMask, frame->presentMask);
    EXPECT_EQ(obs.sequenceNumber, frame->sequenceNumber);
    EXPECT_EQ(obs.transmitter, frame->transmitter);
    EXPECT_EQ(obs.chanspec.asString(), frame->chanspec.asString());
    EXPECT_EQ(obs.routerAddress, "rx-a");
    // Cut bytes and surplus bytes are refused with what and where.
    EXPECT_FALSE(ros1::deserialize(bytes.data(), bytes.size() - 9, back, why));
    EXPECT_NE(why.find("needs"), std::string::npos) << why;
    auto longer = bytes;
    longer.push_back(0);
    EXPECT_FALSE(ros1::deserialize(longer.data(), longer.size(), back, why));
    EXPECT_NE(why.find("left over"), std::string::npos) << why;
    // Sizes that disagree with each other.
    auto bad = msg;
    bad.nSub = 128;  // 80 MHz is 256
    EXPECT_FALSE(ros1::toObservation(bad, obs, why));
    bad = msg;
    bad.csiImag.pop_back();
    EXPECT_FALSE(ros1::toObservation(bad, obs, why));
    EXPECT_NE(why.find("n_sub"), std::string::npos) << why;
}

namespace
{
const std::string kPython = "/usr/bin/python3";

std::string wirosBagScript()
{
    return kPython + " " + test::sourceDir() + "/tests/sensor/wiros_bag.py";
}

bool bagSupport()
{
#if MRPT_WIFI_HAVE_ROSBAG
    return true;
#else
    return false;
#endif
}
}  // namespace

TEST(RosBag, WirosRecordingInAndBackOutEqualForRosTools)
{
    if (!bagSupport()) GTEST_SKIP() << "built without librosbag (scripts/install-deps.sh)";
    test::TempDir tmp;
    const auto write = test::run(wirosBagScript() + " write " + tmp.file("wiros.bag"));
    ASSERT_EQ(write.exitCode, 0) << "python3-rosbag / python3-genpy missing? " << write.output;

    // In: every rf_msgs/Wifi by type (two topics), receivers apart, the bad one counted.
    const auto in = test::run(
        test::binDir() + "/csi-import -q " + tmp.file("wiros.bag") + " " + tmp.file("w.rawlog"));
    EXPECT_EQ(in.exitCode, 3) << in.output;  // one malformed message skipped
    EXPECT_NE(
        in.output.find("format: rosbag, records 6 (1 without CSI skipped)"), std::string::npos)
        << in.output;
    EXPECT_NE(
        in.output.find("skipped 1 malformed record: rf_msgs/Wifi whose sizes disagree"),
        std::string::npos)
        << in.output;
    EXPECT_NE(in.output.find("'192.168.50.2' -> WIFI_CSI_192.168.50.2"), std::string::npos)
        << in.output;
    std::vector<CObservationWiFiCSI::Ptr> frames;
    decodeCsiFile(tmp.file("w.rawlog"), "auto", {}, [&](auto&& f) { frames.push_back(f); });
    ASSERT_EQ(frames.size(), 5u);
    size_t rx1 = 0;
    for (const auto& f : frames)
    {
        const unsigned rxIndex = f->sensorLabel == "WIFI_CSI_192.168.50.2" ? 1 : 0;
        rx1 += rxIndex;
        EXPECT_EQ(f->chanspec.asString(), "155/80");
        EXPECT_EQ(f->nTx, 4);
        EXPECT_EQ(f->presentPairs(), 12u);  // stream 3 was all zeros: absent
        const unsigned msg = f->firmwareCounter;
        for (unsigned tx : {0u, 2u})
            for (unsigned rx : {1u, 3u})
                for (unsigned k : {0u, 37u, 255u})
                {
                    // wiros_bag.py's csi_value(): column-major n_sub x n_rows x n_cols.
                    const float v =
                        float(rxIndex * 4096 + msg * 512 + tx * 128 + rx * 32 + (k % 32)) * 0.5f;
                    EXPECT_EQ(f->at(tx, rx, k), CObservationWiFiCSI::Complex(v, -v))
                        << f->sensorLabel << " msg " << msg << " tx " << tx << " rx " << rx;
                }
        EXPECT_EQ(f->sequenceNumber, 100 + msg);
    }
    EXPECT_EQ(rx1, 2u);
    const auto strict = test::run(
        test::binDir() + "/csi-import -q --strict " + tmp.file("wiros.bag") + " " +
        tmp.file("s.rawlog"));
    EXPECT_EQ(strict.exitCode, 1) << strict.output;
    EXPECT_NE(strict.output.find("message 6 (/csi"), std::string::npos) << strict.output;

    // Out: the frames back as rf_msgs/Wifi, equal field by field to what ROS wrote, and
    // readable by rostopic.
    const auto out = test::run(
        test::binDir() + "/csi-export -q " + tmp.file("w.rawlog") + " --bag " +
        tmp.file("back.bag"));
    ASSERT_EQ(out.exitCode, 0) << out.output;
    const auto same =
        test::run(wirosBagScript() + " same " + tmp.file("wiros.bag") + " " + tmp.file("back.bag"));
    EXPECT_EQ(same.exitCode, 0) << same.output;
    EXPECT_NE(same.output.find("5 rf_msgs/Wifi equal field by field"), std::string::npos)
        << same.output;
    const auto echo = test::run("rostopic echo -b " + tmp.file("back.bag") + " -n 1 /csi");
    EXPECT_EQ(echo.exitCode, 0) << echo.output;
    EXPECT_NE(echo.output.find("rx_id: \"192.168.50.1\""), std::string::npos)
        << echo.output.substr(0, 400);
}

TEST(RosBag, BearingsGoOutAsRfMsgsBearing)
{
    if (!bagSupport()) GTEST_SKIP() << "built without librosbag (scripts/install-deps.sh)";
    test::TempDir tmp;
    const std::vector<double> aoas = {0.25, -1.0, 0.125};
    {
        mrpt::io::CFileGZOutputStream f(tmp.file("b.rawlog"));
        auto ar = mrpt::serialization::archiveFrom(f);
        ar << *test::syntheticFrame(4, 1, 80, 1);
        for (size_t i = 0; i < aoas.size(); ++i)
        {
            CObservationWiFiBearing b;
            b.timestamp = mrpt::Clock::fromDouble(1700000000.0 + double(i));
            b.transmitter = MacAddress::fromString("02:00:00:00:0a:01");
            b.chanspec = Chanspec::make(155, 80);
            b.aoa_rad = aoas[i];
            ar << b;
        }
    }
    const auto out = test::run(
        test::binDir() + "/csi-export -q " + tmp.file("b.rawlog") + " --bag " + tmp.file("b.bag"));
    ASSERT_EQ(out.exitCode, 0) << out.output;
    EXPECT_NE(
        out.output.find("1 rf_msgs/Wifi on /csi, 3 rf_msgs/Bearing on /bearing"), std::string::npos)
        << out.output;
    const auto check =
        test::run(wirosBagScript() + " bearings " + tmp.file("b.bag") + " 0.25 -1.0 0.125");
    EXPECT_EQ(check.exitCode, 0) << check.output;
    // Not a bag: a clear error, exit 1.
    std::ofstream(tmp.file("fake.bag")) << "#ROSBAG V2.0\ngarbage";
    const auto bad = test::run(
        test::binDir() + "/csi-import -q " + tmp.file("fake.bag") + " " + tmp.file("f.rawlog"));
    EXPECT_EQ(bad.exitCode, 1) << bad.output;
    EXPECT_NE(bad.output.find("fake.bag"), std::string::npos) << bad.output;
}
