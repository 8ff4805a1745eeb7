/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <string>
#include <string_view>

/** The text lines Espressif's esp-csi examples print on the serial port (and tools log to
 * .csv): `CSI_DATA,<metadata>,[imag real imag real ...]` with the int8 buffer of
 * wifi_csi_info_t. The L-LTF of the primary 20 MHz channel comes first, 64 subcarriers in
 * FFT order (k = 0..31, −32..−1). */
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
    unsigned len = 0;            //!< int8 values announced
    std::vector<int8_t> values;  //!< the buffer, imag then real per subcarrier
};

/** True for a line that is a CSI record (starts with CSI_DATA). */
bool isCsiLine(std::string_view line);
/** Parses one CSI_DATA line. Never throws: false with `why` for a malformed one. */
bool parseLine(std::string_view line, Esp32Line& out, std::string& why);
/** L-LTF subcarriers that carry a measurement: −26..−1, 1..26. */
const std::vector<int>& lltfSubcarriers();
/** Fills an observation (20 MHz, 1 × 1, the L-LTF) from a parsed line; false with `why` for a
 * channel that doesn't exist or a buffer shorter than the L-LTF. */
bool toObservation(const Esp32Line& l, CObservationWiFiCSI& obs, std::string& why);

}  // namespace mrpt_wifi::esp32
