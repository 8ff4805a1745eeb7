/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <string>
#include <string_view>

/** The text lines Espressif's esp-csi examples print on the serial port (and tools log to
 * .csv): `CSI_DATA,<metadata>,[imag real imag real ...]` with the int8 buffer of
 * wifi_csi_info_t. The buffer holds up to three training fields, in this order: L-LTF, HT-LTF,
 * STBC-HT-LTF; which ones, and over which subcarriers, depends on the secondary channel, the
 * packet's signal mode (non-HT / HT), its bandwidth (cwb) and STBC — ESP-IDF's "Wi-Fi Channel
 * State Information" table (classic ESP32 / S2 / S3 / C3), which bufferLayout() encodes. */
namespace mrpt_wifi::esp32
{
/** Metadata layouts by field count before the bracket:
 *  24: esp-csi get-started (type,seq,mac,rssi,rate,sig_mode,mcs,cwb,smoothing,not_sounding,
 *      aggregation,stbc,fec_coding,sgi,noise_floor,ampdu_cnt,channel,secondary_channel,
 *      local_timestamp,ant,sig_len,rx_state,len,first_word_invalid);
 *  25: ESP32-CSI-Tool (type,role,mac,... as 24 without seq, + real_time_set,real_timestamp,len);
 *  14: esp-csi for ESP32-C5/C6 (type,seq,mac,rssi,rate,noise_floor,fft_gain,agc_gain,channel,
 *      local_timestamp,sig_len,rx_state,len,first_word). */
struct Esp32Line
{
    unsigned metadataFields = 0;
    uint32_t seq = 0;
    MacAddress mac;
    int rssi = 0;
    int noiseFloor = 0;
    bool hasAgc = false;
    int agcGain = 0;
    unsigned channel = 0;
    int secondaryChannel = 0;
    uint64_t localTimestamp_us = 0;
    /** rx_ctrl fields that select the buffer layout (24- and 25-field layouts only). */
    bool hasPacketInfo = false;
    unsigned sigMode = 0;  //!< 0 non-HT (11b/g), 1 HT (11n), 3 VHT
    unsigned cwb = 0;      //!< 0 20 MHz, 1 40 MHz
    unsigned stbc = 0;
    bool firstWordInvalid = false;  //!< the first four bytes of the buffer are not CSI
    /** The layout has no first_word_invalid field (ESP32-CSI-Tool): firstWordInvalid is the
     *  ESP32's usual true, assumed. */
    bool firstWordAssumed = false;
    unsigned len = 0;            //!< int8 values announced
    std::vector<int8_t> values;  //!< the buffer, imag then real per subcarrier
    /** `len` announced more than the line holds, and what it holds is exactly the L-LTF
     *  (ESP32-CSI-Tool logs HT frames so): only the L-LTF is read. */
    bool shorterThanAnnounced = false;
};

/** True for a line that is a CSI record (starts with CSI_DATA). */
bool isCsiLine(std::string_view line);
/** Parses one CSI_DATA line. Never throws: false with `why` (and `reason`, a short category
 *  for counting) for a malformed one. */
bool parseLine(
    std::string_view line, Esp32Line& out, std::string& why, std::string* reason = nullptr);
/** L-LTF subcarriers that carry a measurement (20 MHz channel): −26..−1, 1..26. */
const std::vector<int>& lltfSubcarriers();

/** One training field of the buffer: its entries ((imag, real) pairs) start at `firstEntry`;
 *  entry i is subcarrier k[i], indexed on the layout's channel (the 20 MHz FFT without a
 *  secondary channel, the 40 MHz FFT with one). */
struct LtfBlock
{
    enum class Kind : uint8_t
    {
        LLTF,
        HTLTF,
        STBC_HTLTF
    } kind = Kind::LLTF;
    size_t firstEntry = 0;
    std::vector<int> k;
    /** Subcarriers the field measures, ascending: L-LTF ±1..±26 of the primary 20 MHz, HT-LTF
     *  ±1..±28 of it (20 MHz packets) or ±2..±58 (40 MHz packets); pilots included. */
    std::vector<int> measured;
};
const char* toString(LtfBlock::Kind k);

/** The training fields ESP-IDF's table gives for the line's packet (secondary channel,
 *  sig_mode, cwb, stbc) and the bandwidth they are indexed on (20, or 40 with a secondary
 *  channel). When the buffer length doesn't match the table (a field disabled in
 *  wifi_csi_config_t, or a chip with another table) only the leading L-LTF is returned, and
 *  `matchedTable` is false. */
struct BufferLayout
{
    unsigned bandwidthMHz = 20;
    int primaryOffset = 0;  //!< k of the primary 20 MHz centre: 0, +32 (secondary below), −32
    bool matchedTable = false;
    std::vector<LtfBlock> blocks;
};
BufferLayout bufferLayout(const Esp32Line& l);

/** Fills an observation from a parsed line: the HT-LTF when the line has one (1 × 1, or 2 × 1
 *  with STBC: the STBC-HT-LTF is the second space-time stream), else (or with `legacyLtfOnly`)
 *  the L-LTF; 20 MHz, or 40 MHz around the primary channel when there is a secondary one.
 *  False with `why` for a channel that doesn't exist or a buffer shorter than the L-LTF. */
bool toObservation(
    const Esp32Line& l, CObservationWiFiCSI& obs, std::string& why, bool legacyLtfOnly = false);

}  // namespace mrpt_wifi::esp32
