/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// WiROS's ROS 1 messages (package rf_msgs: Wifi, Bearing) in ROS 1 wire format, and their
// conversion to and from this project's observations. The wire format needs no ROS library;
// reading and writing .bag files does (RosBag.h).

#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <cstdint>
#include <string>
#include <vector>

namespace mrpt_wifi::ros1
{
/** std_msgs/Header. */
struct Header
{
    uint32_t seq = 0;
    uint32_t stampSec = 0, stampNsec = 0;
    std::string frameId;
};

/** rf_msgs/Wifi: the CSI of one frame as WiROS's CSI node publishes it (topic /csi). The matrix
 *  is n_sub × n_rows × n_cols flattened column-major (subcarrier fastest, then receive antenna,
 *  then transmit stream), subcarriers in frequency order (fft-shifted: element i is subcarrier
 *  i − n_sub/2), exactly this project's CObservationWiFiCSI layout. */
struct WifiMessage
{
    Header header;
    uint8_t apId = 0;
    std::vector<uint8_t> txmac;
    uint8_t chan = 0;  //!< channel number
    uint32_t nSub = 0;
    uint8_t nRows = 0, nCols = 0;  //!< receive antennas, transmit streams
    uint8_t bw = 0;                //!< MHz
    uint8_t mcs = 0;
    int32_t rssi = 0;
    uint32_t fc = 0;      //!< frame control byte
    uint32_t seqNum = 0;  //!< 802.11 sequence control (seq << 4 | frag), as nexmon reports it
    std::vector<double> csiReal, csiImag;
    std::string rxId;  //!< which receiver (WiROS: the router's address)
    uint32_t msgId = 0;
};

/** rf_msgs/Bearing (topic /bearing): WiROS's processing node puts one AoA [rad] in `aoa`. */
struct BearingMessage
{
    Header header;
    uint8_t apId = 0;
    std::vector<uint8_t> txmac;
    uint8_t nTx = 0, nRx = 0;
    uint32_t seq = 0;
    std::vector<int32_t> rssi;
    std::vector<double> aoa;
};

/** Message type names, definitions (as a bag's connection header carries them, dependencies
 *  included) and MD5 sums (ROS 1's: over the definition with comments removed and each nested
 *  type replaced by its MD5). */
struct MessageType
{
    std::string datatype, md5, definition;
};
const MessageType& wifiType();
const MessageType& bearingType();
/** The rf_msgs field lines (Wifi.msg, Bearing.msg without comments; nested types spelled as ROS
 *  1 does, "std_msgs/Header header"). The ROS 2 package has the same fields (Ros2Messages.h). */
const char* wifiFieldLines();
const char* bearingFieldLines();
/** ROS 1's MD5 of a message definition body (field lines; nested types already as their MD5s
 *  where given in `nested`, a map from type name to MD5). Exposed for tests. */
std::string messageMd5(
    const std::string& definition, const std::vector<std::pair<std::string, std::string>>& nested);

/** ROS 1 wire format (little-endian; arrays and strings prefixed by a uint32 count). */
std::vector<uint8_t> serialize(const WifiMessage& m);
std::vector<uint8_t> serialize(const BearingMessage& m);
/** Parse; false with `why` when the bytes end early, a count runs past them, or bytes are left
 *  over. */
bool deserialize(const uint8_t* data, size_t len, WifiMessage& out, std::string& why);
bool deserialize(const uint8_t* data, size_t len, BearingMessage& out, std::string& why);

/** A Wifi message as an observation. False with `why` (the observation untouched) when the
 *  message's own sizes disagree: csi arrays not n_sub·n_rows·n_cols long, n_sub not the FFT
 *  size of bw, a channel/bandwidth pair that does not exist, more than 8 chains. Pairs whose
 *  values are all zero (WiROS fills the 4×4 matrix) are marked absent. */
bool toObservation(const WifiMessage& m, CObservationWiFiCSI& obs, std::string& why);
/** An observation as a Wifi message (header stamp = the observation's timestamp). */
WifiMessage fromObservation(const CObservationWiFiCSI& obs, const std::string& rxId);
/** A bearing as a Bearing message (aoa = [AoA in the receive array's frame, rad], rssi =
 *  [dBm]; n_tx / n_rx 0: a bearing does not carry the array sizes). */
BearingMessage fromBearing(const CObservationWiFiBearing& b);

}  // namespace mrpt_wifi::ros1
