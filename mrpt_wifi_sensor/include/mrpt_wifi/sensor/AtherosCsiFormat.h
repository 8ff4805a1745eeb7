/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <cstddef>
#include <cstdint>
#include <string>

/** The Atheros CSI Tool's log (recvCSI on ath9k AR93xx, as its MATLAB read_log_file reads it):
 * records of a little-endian uint16 length, then that many bytes: a 25-byte status (uint64
 * timestamp, uint16 csi_len, uint16 channel [MHz], uint8 phy error, noise floor, rate,
 * bandwidth (0 = 20, 1 = 40 MHz), number of tones (56 / 114), nr (receive antennas), nc
 * (transmit streams), RSSI, RSSI of chains 0–2, uint16 payload_len), csi_len bytes of CSI and
 * payload_len bytes of the frame's payload. The CSI is a little-endian bit stream of 10-bit
 * two's-complement values, per tone, per nc, per nr: imaginary then real.
 *
 * The byte order is the recording host's: logs written on a big-endian router differ. This
 * decoder reads the little-endian logs of the tool's x86 user-space app. */
namespace mrpt_wifi::atheros
{
constexpr size_t kStatusBytes = 25;
constexpr unsigned kMaxAntennas = 3;

struct AtherosRecord
{
    uint64_t timestamp = 0;  //!< TSF [µs]
    uint16_t csiLen = 0;
    uint16_t channel_MHz = 0;
    uint8_t phyError = 0, noiseFloor = 0, rate = 0, bandwidth = 0, tones = 0;
    uint8_t nr = 0, nc = 0;
    uint8_t rssi = 0;
    uint8_t chainRssi[3] = {0, 0, 0};
    uint16_t payloadLen = 0;
    /** CSI [nr][nc][tone] as read_csi returns it (tone fastest last), integers. */
    std::vector<std::complex<float>> csi;
    std::complex<float> at(unsigned r, unsigned c, unsigned tone) const
    {
        return csi[(size_t(tone) * nc + c) * nr + r];
    }
};

/** Parses the record body (the `length` bytes after the uint16 length). Never throws: false
 * with `why` for a body whose sizes don't add up, impossible antenna or tone counts. */
bool parseRecord(
    const uint8_t* body, size_t length, AtherosRecord& out, std::string& why,
    std::string* reason = nullptr);

/** Subcarrier of each reported tone, ascending: HT20 −28..−1, 1..28 (56 tones), HT40
 *  −58..−2, 2..58 (114). */
const std::vector<int>& toneSubcarriers(unsigned tones);

/** Fills an observation (nr receive antennas × nc streams) from a record with CSI; false with
 * `why` for a channel frequency that is no WiFi channel. */
bool toObservation(const AtherosRecord& r, CObservationWiFiCSI& obs, std::string& why);

}  // namespace mrpt_wifi::atheros
