/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/RosBag.h>

#include <cstring>
#include <map>
#include <set>

namespace mrpt_wifi
{
namespace
{
/** WiROS recordings: rf_msgs/Wifi messages in a ROS 1 bag, found by type on any topic. */
class RosBagDecoder : public CsiDecoder
{
public:
    std::string name() const override { return "rosbag"; }
    std::string description() const override
    {
        return "ROS 1 bag of WiROS's rf_msgs/Wifi (any topic; receivers apart by rx_id)";
    }
    int probe(const uint8_t* head, size_t len) const override
    {
        static const char kMagic[] = "#ROSBAG V2.0\n";
        return len >= sizeof(kMagic) - 1 && std::memcmp(head, kMagic, sizeof(kMagic) - 1) == 0 ? 100
                                                                                               : 0;
    }
    void decodeFile(
        const std::string& path, const CsiDecodeOptions& options, const CsiFrameSink& onFrame,
        const CsiProgress& onProgress, CsiDecodeSummary& summary) const override
    {
        const auto& wifi = ros1::wifiType();
        std::map<std::string, uint64_t> topics;        // rf_msgs/Wifi per topic
        std::map<std::string, std::string> receivers;  // rx_id -> sensor label
        std::set<std::string> otherTypes;
        uint64_t index = 0;
        ros1::forEachBagMessage(
            path,
            [&](const ros1::BagMessage& m)
            {
                const uint64_t at = index++;
                // Only a rejected message needs its position in words.
                const auto where = [&]
                {
                    return "message " + std::to_string(at) + " (" + m.topic +
                           ", t=" + std::to_string(m.time) + ")";
                };
                if (m.datatype != wifi.datatype)
                {
                    ++summary.skipped;
                    otherTypes.insert(m.datatype);
                    return;
                }
                ++summary.records;
                if (m.md5 != wifi.md5)
                    return rejectRecord(
                        path, name(), options, summary, at,
                        "rf_msgs/Wifi of another definition (MD5 " + m.md5 + ", expected " +
                            wifi.md5 + ")",
                        {}, where());
                ros1::WifiMessage w;
                std::string why;
                if (!ros1::deserialize(m.bytes.data(), m.bytes.size(), w, why))
                    return rejectRecord(
                        path, name(), options, summary, at, "malformed rf_msgs/Wifi", why, where());
                auto obs = CObservationWiFiCSI::Create();
                if (!ros1::toObservation(w, *obs, why))
                    return rejectRecord(
                        path, name(), options, summary, at, "rf_msgs/Wifi whose sizes disagree",
                        why, where());
                // WiROS stamps each message when it is received; a zero stamp: the bag's time.
                if (w.header.stampSec == 0 && w.header.stampNsec == 0)
                    obs->timestamp = mrpt::Clock::fromDouble(m.time);
                const std::string& label = options.assembler.sensorLabel;
                obs->sensorLabel = w.rxId.empty() ? label : label + "_" + w.rxId;
                receivers[w.rxId] = obs->sensorLabel;
                obs->sensorPose = options.assembler.sensorPose;
                topics[m.topic]++;
                ++summary.frames;
                onFrame(std::move(obs));
            },
            onProgress);
        std::string d = "rosbag: rf_msgs/Wifi on";
        for (const auto& [t, n] : topics) d += " " + t + " (" + std::to_string(n) + ")";
        if (topics.empty()) d += " no topic";
        d += "; receivers (rx_id -> sensor label):";
        for (const auto& [rx, l] : receivers) d += " '" + rx + "' -> " + l;
        if (!otherTypes.empty())
        {
            d += "; other message types skipped:";
            for (const auto& t : otherTypes) d += " " + t;
        }
        summary.details = d;
        summary.noteOnce(
            "rf_msgs/Wifi seq_num read as the 802.11 sequence control (seq << 4 | frag), chan as "
            "the centre or control channel of its bandwidth");
    }
};
}  // namespace
}  // namespace mrpt_wifi

using mrpt_wifi::RosBagDecoder;
MRPT_WIFI_REGISTER_CSI_DECODER(RosBagDecoder)
