/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/McapReader.h>
#include <mrpt_wifi/sensor/Ros2Messages.h>
#include <mrpt_wifi/sensor/Rosbag2Reader.h>

#include <cstring>
#include <map>
#include <set>

namespace mrpt_wifi
{
namespace
{
/** WiROS's ROS 2 recordings: rf_msgs/msg/Wifi (CDR) in a rosbag2 bag, MCAP or SQLite, found by
 *  type on any topic. */
class Rosbag2Decoder : public CsiDecoder
{
public:
    std::string name() const override { return "rosbag2"; }
    std::string description() const override
    {
        return "ROS 2 bag (MCAP .mcap, SQLite .db3, or the bag directory) of WiROS's "
               "rf_msgs/msg/Wifi (any topic; receivers apart by rx_id)";
    }
    int probe(const uint8_t* head, size_t len) const override
    {
        if (mcap::hasMcapMagic(head, len)) return 100;
        // Any SQLite database: decodeFile says so if it has no rosbag2 tables.
        static const char kSqlite[] = "SQLite format 3";
        return len >= sizeof(kSqlite) && std::memcmp(head, kSqlite, sizeof(kSqlite)) == 0 ? 80 : 0;
    }
    void decodeFile(
        const std::string& path, const CsiDecodeOptions& options, const CsiFrameSink& onFrame,
        const CsiProgress& onProgress, CsiDecodeSummary& summary) const override
    {
        const auto& wifi = ros2::wifiType();
        std::map<std::string, uint64_t> topics;        // rf_msgs/msg/Wifi per topic
        std::map<std::string, std::string> receivers;  // rx_id -> sensor label
        std::map<std::string, uint64_t> otherTypes;
        // Each distinct schema text is compared once: text -> why it differs ("" = same).
        std::map<std::string, std::string> definitionChecks;
        ros2::BagReadStats bag;
        const auto onMessage = [&](const ros2::BagMessage& m)
        {
            if (m.type != wifi.name)
            {
                ++summary.skipped;
                ++otherTypes[m.type.empty() ? "(no schema)" : m.type];
                return;
            }
            ++summary.records;
            const auto reject = [&](const std::string& reason, const std::string& detail)
            { rejectRecord(m.file, name(), options, summary, m.offset, reason, detail, m.where); };
            if (m.serializationFormat != "cdr")
                return reject(
                    "rf_msgs/msg/Wifi not CDR-encoded",
                    "serialization format '" + m.serializationFormat + "'");
            if (m.definition)
            {
                auto check = definitionChecks.find(*m.definition);
                if (check == definitionChecks.end())
                {
                    std::string why;
                    if (m.definitionEncoding != "ros2msg")
                        why = "definition encoded as '" + m.definitionEncoding + "', not ros2msg";
                    else if (ros2::sameDefinition(wifi, *m.definition, why))
                        why.clear();
                    check = definitionChecks.emplace(*m.definition, why).first;
                }
                if (!check->second.empty())
                    return reject("rf_msgs/msg/Wifi of another definition", check->second);
            }
            ros1::WifiMessage w;
            std::string why;
            if (!ros2::deserializeCdr(m.data, m.size, w, why))
                return reject("malformed rf_msgs/msg/Wifi", why);
            auto obs = CObservationWiFiCSI::Create();
            if (!ros1::toObservation(w, *obs, why))
                return reject("rf_msgs/msg/Wifi whose sizes disagree", why);
            // WiROS stamps each message when it is received; a zero stamp: the bag's time.
            if (w.header.stampSec == 0 && w.header.stampNsec == 0)
                obs->timestamp = mrpt::Clock::fromDouble(double(m.timeNs) * 1e-9);
            const std::string& label = options.assembler.sensorLabel;
            obs->sensorLabel = w.rxId.empty() ? label : label + "_" + w.rxId;
            receivers[w.rxId] = obs->sensorLabel;
            obs->sensorPose = options.assembler.sensorPose;
            topics[m.topic]++;
            ++summary.frames;
            onFrame(std::move(obs));
        };
        const auto describe = [&]
        {
            std::string d = "rosbag2: " + bag.asString() + "\nrf_msgs/msg/Wifi on";
            for (const auto& [t, n] : topics) d += " " + t + " (" + std::to_string(n) + ")";
            if (topics.empty()) d += " no topic";
            d += "; receivers (rx_id -> sensor label):";
            for (const auto& [rx, l] : receivers) d += " '" + rx + "' -> " + l;
            if (!otherTypes.empty())
            {
                d += "; other message types skipped:";
                for (const auto& [t, n] : otherTypes) d += " " + t + " (" + std::to_string(n) + ")";
            }
            summary.details = d;
            summary.noteOnce(
                "rf_msgs/msg/Wifi seq_num read as the 802.11 sequence control (seq << 4 | frag), "
                "chan as the centre or control channel of its bandwidth");
        };
        try
        {
            ros2::forEachBagMessage(path, onMessage, onProgress, &bag);
        }
        catch (...)
        {
            describe();  // the summary says what was read before the fault
            throw;
        }
        describe();
    }
};
}  // namespace
}  // namespace mrpt_wifi

using mrpt_wifi::Rosbag2Decoder;
MRPT_WIFI_REGISTER_CSI_DECODER(Rosbag2Decoder)
