/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// WiROS's messages (rf_msgs Wifi, Bearing) as ROS 2 carries them: CDR (XCDR1, little-endian,
// through Debian's libfastcdr) and ros2msg definitions as rosbag2 stores them in MCAP schemas.
// The fields and their meanings are those of the ROS 1 structs (RosMessages.h); ROS 2's
// std_msgs/msg/Header has no seq (Header::seq is ignored when writing and 0 after reading).

#include <mrpt_wifi/sensor/RosMessages.h>

#include <cstdint>
#include <string>
#include <vector>

namespace mrpt_wifi::ros2
{
/** A ROS 2 message type: its name ("rf_msgs/msg/Wifi") and its ros2msg definition with the
 *  definitions it depends on appended in "====…\nMSG: pkg/msg/Type\n" blocks, the way rosbag2's
 *  MCAP storage writes a schema. */
struct MessageType
{
    std::string name;
    std::string definition;
};
const MessageType& wifiType();
const MessageType& bearingType();

/** True when `definition` (ros2msg text, as a schema carries it) declares the same fields as
 *  `type`'s, recursively through its dependencies: comments, blank lines, spacing, default
 *  values, constants and the spelling of type names (std_msgs/Header, std_msgs/msg/Header,
 *  Header) do not matter. False with `why` naming the first difference. */
bool sameDefinition(const MessageType& type, const std::string& definition, std::string& why);

/** The CDR form of a serialized ROS 2 message: the 4-byte encapsulation header
 *  (00 01 00 00, CDR little-endian) followed by the XCDR1 body. */
std::vector<uint8_t> serializeCdr(const ros1::WifiMessage& m);
std::vector<uint8_t> serializeCdr(const ros1::BearingMessage& m);
/** Parse; false with `why` (naming the field and byte offset) when the encapsulation is not
 *  plain CDR, the bytes end early, a count runs past them, or more than alignment padding (3
 *  bytes) is left over. */
bool deserializeCdr(const uint8_t* data, size_t len, ros1::WifiMessage& out, std::string& why);
bool deserializeCdr(const uint8_t* data, size_t len, ros1::BearingMessage& out, std::string& why);

}  // namespace mrpt_wifi::ros2
