// libFuzzer target for WiROS's ROS 1 messages (rf_msgs/Wifi, rf_msgs/Bearing): arbitrary bytes
// as a serialized message, as a bag's record would hand them to csi-import. Bad bytes must be
// refused (false with a reason), never crash, leak or give a frame whose shape disagrees with
// its data.
#include <mrpt_wifi/sensor/RosMessages.h>

#include <cstdint>

using namespace mrpt_wifi;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    std::string why;
    ros1::WifiMessage w;
    if (ros1::deserialize(data, size, w, why))
    {
        CObservationWiFiCSI obs;
        if (ros1::toObservation(w, obs, why))
        {
            if (obs.csi.size() != size_t(obs.nTx) * obs.nRx * obs.nfft()) __builtin_trap();
            // What was read must serialize back to the same bytes.
            if (ros1::serialize(w) != std::vector<uint8_t>(data, data + size)) __builtin_trap();
        }
    }
    ros1::BearingMessage b;
    if (ros1::deserialize(data, size, b, why) &&
        ros1::serialize(b) != std::vector<uint8_t>(data, data + size))
        __builtin_trap();
    return 0;
}
