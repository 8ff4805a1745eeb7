/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

/** The Linux 802.11n CSI Tool's `.dat` log of the Intel 5300 (log_to_file): records of a
 * big-endian uint16 length, a code byte and length−1 bytes; code 0xBB (187) is a beamforming
 * report with 30 grouped subcarriers × Ntx × Nrx int8 I/Q, as read by the tool's read_bfee.c. */
namespace mrpt_wifi::intel5300
{
constexpr uint8_t kCodeBeamforming = 0xBB;
constexpr size_t kBfeeHeaderBytes = 20;
constexpr unsigned kSubcarriers = 30;
constexpr unsigned kMaxAntennas = 3;
constexpr uint16_t kRateHt40 = 0x0800;  //!< RATE_MCS_HT40_MSK of rate_n_flags

/** Extra bytes the WSR Toolbox's CSI logger (github Harvard-REACT) puts between the 20-byte
 *  header and the CSI of its 0xBB records: the logging host's time (uint32 s, uint32 µs), the
 *  sender's MAC address and the sender's frame counter (uint32), all little-endian. The
 *  counter pairs a packet heard by one robot with the reply heard by the other. */
constexpr size_t kWsrExtraBytes = 18;
struct WsrTrailer
{
    double hostTime_s = 0;  //!< the logging computer's clock (gettimeofday) [s]
    std::array<uint8_t, 6> senderMac{};
    uint32_t frameCount = 0;  //!< the sender's packet counter
};

/** One decoded beamforming record (the fields of read_bfee + the permuted CSI). */
struct BfeeRecord
{
    uint32_t timestampLow = 0;  //!< NIC clock [µs]
    uint16_t bfeeCount = 0;
    uint8_t nRx = 0, nTx = 0;
    std::array<uint8_t, 3> rssi{};  //!< rssi_a/b/c [dB]
    int8_t noise = 0;               //!< [dBm]; −127 = not measured
    uint8_t agc = 0;                //!< [dB]
    std::array<uint8_t, 3> perm{};  //!< antenna permutation, 0-based
    bool permValid = false;         //!< perm is a permutation of 0..nRx−1 (else not applied)
    uint16_t rate = 0;              //!< rate_n_flags
    std::optional<WsrTrailer> wsr;  //!< set for the WSR Toolbox's record variant
    /** CSI [tx][rx][subcarrier] as read_bf_file returns it (receive antennas permuted). */
    std::array<std::complex<float>, kMaxAntennas * kMaxAntennas * kSubcarriers> csi{};
    std::complex<float> at(unsigned tx, unsigned rx, unsigned s) const
    {
        return csi[(tx * nRx + rx) * kSubcarriers + s];
    }
    bool ht40() const { return rate & kRateHt40; }
    /** get_total_rss: combined RSSI [dBm]. */
    double totalRss_dBm() const;
    /** get_scaled_csi's factor (scaled = factor · csi). */
    double scaleFactor() const;
};

/** Decodes the payload of a 0xBB record (the bytes after the code): header + CSI, or header +
 * WSR trailer + CSI (told apart by the record's length). Never throws: returns false and sets
 * `why` (and `reason`, a short category for counting) for impossible antenna counts, a payload
 * size not matching them, or a record length that is neither of the two. */
bool parseBfee(
    const uint8_t* data, size_t len, BfeeRecord& out, std::string& why,
    std::string* reason = nullptr);

/** Subcarrier indices of the 30 groups: Ng = 2 at 20 MHz, Ng = 4 at 40 MHz (802.11n). */
const std::array<int, kSubcarriers>& groupedSubcarriers(bool ht40);

/** Fills an observation from a record on `chanspec` (bandwidth from the record's rate). A WSR
 * record also gives the timestamp (host clock), the transmitter (the sender's MAC) and
 * firmwareCounter (the low 16 bits of the sender's frame counter); `source` "iwl5300-wsr". */
void toObservation(const BfeeRecord& r, const Chanspec& chanspec, CObservationWiFiCSI& obs);

}  // namespace mrpt_wifi::intel5300
