/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <complex>
#include <cstddef>
#include <cstdint>
#include <vector>

/** The Nexmon CSI UDP datagram format of the BCM4366c0 (RT-AC86U), DESIGN.md §4. */
namespace mrpt_wifi::nexmon
{
constexpr size_t kHeaderBytes = 18;             //!< header size, identical in all three variants
constexpr size_t kUbiLocateTrailerBytes = 128;  //!< firmware metadata after UbiLocate CSI
constexpr uint16_t kChip4366c0 = 0x006a;
constexpr uint16_t kDefaultUdpPort = 5500;
constexpr unsigned kMaxCores = 4;    //!< receive chains of the 4366c0
constexpr unsigned kMaxStreams = 4;  //!< spatial streams the 4366c0 reports

/** Why a datagram was not accepted. */
enum class RejectReason : uint8_t
{
    TooShort = 0,   //!< shorter than the 18-byte header
    BadMagic,       //!< not 0x1111 / 0x11111111
    UnknownChip,    //!< chip word not the 4366c0's
    BadChanspec,    //!< bandwidth/band/channel impossible
    SizeMismatch,   //!< length doesn't match the bandwidth's NFFT
    BadCoreStream,  //!< core or stream outside the chip / configured masks
    Count
};
const char* toString(RejectReason r);

/** Which header variant to expect; Auto tells them apart by magic and length. */
enum class FormatHint : uint8_t
{
    Auto = 0,
    Nexmon,
    NexmonLegacy,
    UbiLocate
};
const char* toString(FormatHint f);
/** Parses "auto|nexmon|nexmon-legacy|ubilocate"; throws std::invalid_argument otherwise. */
FormatHint formatHintFromString(const std::string& s);

/** The decoded 18-byte header of one datagram: one (core, stream) of one frame. */
struct DatagramHeader
{
    NexmonHeaderVariant variant = NexmonHeaderVariant::Nexmon;
    int8_t rssi_dBm = 0;
    uint8_t frameControl = 0;
    MacAddress transmitter;
    uint16_t sequenceControl = 0;  //!< seq << 4 | fragment
    uint8_t core = 0;
    uint8_t stream = 0;
    Chanspec chanspec;
    uint16_t chipId = 0;           //!< 0x006a for Nexmon / legacy; 0 for UbiLocate
    uint16_t firmwareCounter = 0;  //!< UbiLocate only
    uint8_t coreMask = 0;          //!< UbiLocate only: cores the frame has (0 = not said)
    uint8_t streamMask = 0;        //!< UbiLocate only: streams the frame has (0 = not said)

    uint16_t sequenceNumber() const { return sequenceControl >> 4; }
    uint8_t fragmentNumber() const { return sequenceControl & 0xF; }
    unsigned nfft() const { return chanspec.nfft(); }
};

/** Parses and validates the header of a datagram of `len` bytes (header + CSI words
 * [+ trailer]). Never throws: returns false and sets `why` for a malformed datagram. */
bool parseHeader(
    const uint8_t* data, size_t len, FormatHint hint, DatagramHeader& out, RejectReason& why);

/** Byte offset of the CSI words in every variant. */
constexpr size_t csiOffset()
{
    return kHeaderBytes;
}
/** Datagram length for a variant and FFT size. */
size_t datagramSize(NexmonHeaderVariant v, unsigned nfft);

/** One 4366c0 packed-float word → complex value (mantissa · 2^exponent). */
std::complex<float> unpackWord(uint32_t w);
/** Complex value → the nearest packed-float word (11-bit mantissas, shared 6-bit exponent). */
uint32_t packWord(std::complex<float> v);

/** Decodes `nfft` little-endian words (raw FFT order) into `out` in subcarrier order
 * (fftshift: raw index i goes to bin (i + nfft/2) mod nfft). */
void decodeWords(const uint8_t* words, unsigned nfft, std::complex<float>* out);

/** Encodes one datagram from CSI in subcarrier order (nfft = h.nfft() values). `out` is
 * resized to datagramSize(h.variant, nfft); the UbiLocate trailer is zero. */
void encodeDatagram(
    const DatagramHeader& h, const std::complex<float>* subcarrierOrder, std::vector<uint8_t>& out);

/** Header of the datagram carrying pair (tx, rx) of an observation. */
DatagramHeader headerFor(const CObservationWiFiCSI& obs, unsigned tx, unsigned rx);

/** Every datagram of a frame as the router sends them: one per present (core, stream), core
 * by core, streams within a core (the order of the real captures). */
std::vector<std::vector<uint8_t>> encodeFrame(const CObservationWiFiCSI& obs);

}  // namespace mrpt_wifi::nexmon
