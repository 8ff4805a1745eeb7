/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/CObservationWiFiCSI.h>

#include <complex>
#include <cstddef>
#include <cstdint>
#include <vector>

/** The Nexmon CSI UDP datagram format (DESIGN.md §4) of the four chips nexmon_csi supports:
 * BCM4366c0 (RT-AC86U), BCM43455c0 (Raspberry Pi 3B+/4/400), BCM4358 (Nexus 6P), BCM4339
 * (Nexus 5). They share the 18-byte header; they differ in the chip word, where the core and
 * stream sit in the csiconf word, and in how a CSI word encodes a complex value. */
namespace mrpt_wifi::nexmon
{
constexpr size_t kHeaderBytes = 18;             //!< header size, identical in all three variants
constexpr size_t kUbiLocateTrailerBytes = 128;  //!< firmware metadata after UbiLocate CSI
constexpr uint16_t kChip4366c0 = 0x006a;
constexpr uint16_t kChip43455c0 = 0x0065;
constexpr uint16_t kChip4358 = 0x0003;
/** The chip word of the BCM4358 in nexmon_csi's own example capture (utils/matlab/example.pcap). */
constexpr uint16_t kChip4358Example = 0xdead;
constexpr uint16_t kChip4339 = 0x0001;

/** A chip nexmon_csi runs on. */
enum class Chip : uint8_t
{
    BCM4366c0 = 0,  //!< packed float: 12-bit sign+mantissa I and Q, 6-bit shared exponent; 4x4
    BCM43455c0,     //!< int16 I and Q; 1 core (Raspberry Pi 3B+/4/400)
    BCM4358,        //!< packed float: 9-bit sign+mantissa I and Q, 5-bit exponent; 2 cores
    BCM4339         //!< int16 I and Q; 1 core
};
const char* toString(Chip c);
/** Chip of a header's chip word; false for an unknown word. */
bool chipFromWord(uint16_t word, Chip& out);
/** Receive cores the chip has. */
unsigned chipCores(Chip c);
/** Bandwidths [MHz] decoded for the chip: 20/40/80 on all four (nexmon_csi), 160 on the
 *  BCM4366c0 (its radio's widest mode; not documented by nexmon_csi). */
bool chipSupportsBandwidth(Chip c, unsigned bandwidthMHz);
constexpr uint16_t kDefaultUdpPort = 5500;
constexpr unsigned kMaxCores = 4;    //!< receive chains of the 4366c0
constexpr unsigned kMaxStreams = 4;  //!< spatial streams the 4366c0 reports

/** Why a datagram was not accepted. */
enum class RejectReason : uint8_t
{
    TooShort = 0,   //!< shorter than the 18-byte header
    BadMagic,       //!< not 0x1111 / 0x11111111
    UnknownChip,    //!< chip word none of the four nexmon_csi chips
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
    uint16_t chipId = 0;           //!< chip word for Nexmon / legacy; 0 for UbiLocate
    Chip chip = Chip::BCM4366c0;   //!< from the chip word (UbiLocate: the 4366c0)
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
/** One BCM4358 packed-float word (8-bit mantissas + signs, 5-bit exponent) → complex value. */
std::complex<float> unpackWord4358(uint32_t w);
/** Complex value → the nearest packed-float word (11-bit mantissas, shared 6-bit exponent). */
uint32_t packWord(std::complex<float> v);

/** Decodes `nfft` little-endian 4366c0 words (raw FFT order) into `out` in subcarrier order
 * (fftshift: raw index i goes to bin (i + nfft/2) mod nfft). */
void decodeWords(const uint8_t* words, unsigned nfft, std::complex<float>* out);
/** As decodeWords() for any chip: int16 I/Q (4339, 43455c0: real in the low half-word),
 * 4358 or 4366c0 packed floats. */
void decodeWords(Chip chip, const uint8_t* words, unsigned nfft, std::complex<float>* out);

/** Encodes one datagram from CSI in subcarrier order (nfft = h.nfft() values). `out` is
 * resized to datagramSize(h.variant, nfft); the UbiLocate trailer is zero. The words follow
 * `h.chip`: 4366c0 packed floats, or int16 I/Q (43455c0, 4339: values rounded and saturated,
 * so scale them first). Throws std::invalid_argument for the 4358 (decode only). */
void encodeDatagram(
    const DatagramHeader& h, const std::complex<float>* subcarrierOrder, std::vector<uint8_t>& out);

/** The chip word nexmon_csi puts in the header of `c`'s datagrams. */
uint16_t chipWord(Chip c);

/** Header of the datagram carrying pair (tx, rx) of an observation, as `chip` sends it. */
DatagramHeader headerFor(
    const CObservationWiFiCSI& obs, unsigned tx, unsigned rx, Chip chip = Chip::BCM4366c0);

/** Every datagram of a frame as the chip sends them: one per present (core, stream), core
 * by core, streams within a core (the order of the real captures). */
std::vector<std::vector<uint8_t>> encodeFrame(
    const CObservationWiFiCSI& obs, Chip chip = Chip::BCM4366c0);

}  // namespace mrpt_wifi::nexmon
