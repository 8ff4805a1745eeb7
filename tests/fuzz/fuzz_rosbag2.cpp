// libFuzzer target for the ROS 2 bag reader: the first byte picks the input kind, the rest is
//   0: an MCAP file (container, chunks with zstd / lz4 / none, CRCs), each rf_msgs/msg/Wifi in it
//      checked and decoded as csi-import does;
//   1: one CDR message, read as rf_msgs/msg/Wifi and as rf_msgs/msg/Bearing;
//   2: ros2msg definition text, compared with rf_msgs/msg/Wifi's.
// Bad bytes must be refused (an exception naming the offset, or false with a reason), never
// crash, leak, allocate what a damaged size claims, or give a frame whose shape disagrees with
// its data. (SQLite bags go through Debian's libsqlite3, fuzzed upstream.)
#include <mrpt_wifi/sensor/Ros2Messages.h>
#include <mrpt_wifi/sensor/Rosbag2Reader.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>

using namespace mrpt_wifi;

namespace
{
void checkFrame(const ros1::WifiMessage& w)
{
    std::string why;
    CObservationWiFiCSI obs;
    if (ros1::toObservation(w, obs, why) &&
        obs.csi.size() != size_t(obs.nTx) * obs.nRx * obs.nfft())
        __builtin_trap();
}

bool hasNul(const std::string& s)
{
    return s.find('\0') != std::string::npos;
}

// Bit for bit: a NaN read must come back as the same NaN.
template <typename T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b)
{
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

void cdrMessage(const uint8_t* data, size_t size)
{
    std::string why;
    ros1::WifiMessage w;
    if (ros2::deserializeCdr(data, size, w, why))
    {
        checkFrame(w);
        // What was read reads back the same after writing (strings with a NUL inside are cut
        // at it by CDR's writer, as by every ROS 2 one).
        if (!hasNul(w.header.frameId) && !hasNul(w.rxId))
        {
            const auto bytes = ros2::serializeCdr(w);
            ros1::WifiMessage again;
            if (!ros2::deserializeCdr(bytes.data(), bytes.size(), again, why)) __builtin_trap();
            if (!sameBits(again.csiReal, w.csiReal) || !sameBits(again.csiImag, w.csiImag) ||
                again.rxId != w.rxId || again.seqNum != w.seqNum || again.txmac != w.txmac ||
                again.header.stampNsec != w.header.stampNsec)
                __builtin_trap();
        }
    }
    ros1::BearingMessage b;
    if (ros2::deserializeCdr(data, size, b, why) && !hasNul(b.header.frameId))
    {
        const auto bytes = ros2::serializeCdr(b);
        ros1::BearingMessage again;
        if (!ros2::deserializeCdr(bytes.data(), bytes.size(), again, why) ||
            !sameBits(again.aoa, b.aoa) || again.rssi != b.rssi)
            __builtin_trap();
    }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size < 1) return 0;
    const uint8_t kind = data[0] % 3;
    ++data, --size;
    if (kind == 0)
    {
        mcap::McapReadOptions options;
        options.maxChunkBytes = 1 << 20;  // a damaged size must not become a huge allocation
        try
        {
            ros2::forEachMcapBagMessage(
                data, size, "fuzz.mcap",
                [](const ros2::BagMessage& m)
                {
                    if (m.type != ros2::wifiType().name) return;
                    std::string why;
                    if (m.definition && !ros2::sameDefinition(ros2::wifiType(), *m.definition, why))
                        return;
                    ros1::WifiMessage w;
                    if (ros2::deserializeCdr(m.data, m.size, w, why)) checkFrame(w);
                },
                nullptr, options);
        }
        catch (const mcap::McapError&)
        {
            // A corrupt file: named with its offset, what came before already delivered.
        }
    }
    else if (kind == 1)
        cdrMessage(data, size);
    else
    {
        std::string why;
        ros2::sameDefinition(
            ros2::wifiType(), std::string(reinterpret_cast<const char*>(data), size), why);
    }
    return 0;
}
