/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// ROS 1 .bag files through Debian's librosbag-storage (only in builds that found it:
// MRPT_WIFI_HAVE_ROSBAG). The messages themselves are RosMessages.h.

#include <mrpt_wifi/sensor/RosMessages.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace mrpt_wifi::ros1
{
/** One message of a bag, as stored (serialized bytes). */
struct BagMessage
{
    std::string topic, datatype, md5;
    double time = 0;  //!< the bag's record time [s]
    std::vector<uint8_t> bytes;
};

/** Calls `onMessage` for every message of the bag in time order; `onProgress(fraction)` now and
 *  then. Throws std::runtime_error naming the file if it can't be opened or read. */
void forEachBagMessage(
    const std::string& path, const std::function<void(const BagMessage&)>& onMessage,
    const std::function<void(double)>& onProgress = {});

/** Writes messages to a new .bag (overwrites). */
class BagWriter
{
public:
    explicit BagWriter(const std::string& path);
    ~BagWriter();
    BagWriter(const BagWriter&) = delete;
    BagWriter& operator=(const BagWriter&) = delete;
    /** `bytes`: the serialized message (taken over: the bag writer reads it in place). */
    void write(
        const std::string& topic, double time, const MessageType& type, std::vector<uint8_t> bytes);
    void close();

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    std::string path_;
};

}  // namespace mrpt_wifi::ros1
