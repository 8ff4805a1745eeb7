/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/sensor/NexmonFormat.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>

#if __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the Nexmon word decoder assumes a little-endian host"
#endif

namespace mrpt_wifi::nexmon
{
namespace
{
inline uint16_t readLE16(const uint8_t* p)
{
    return uint16_t(p[0] | (p[1] << 8));
}
inline void writeLE16(uint8_t* p, uint16_t v)
{
    p[0] = uint8_t(v);
    p[1] = uint8_t(v >> 8);
}
inline void writeLE32(uint8_t* p, uint32_t v)
{
    for (int i = 0; i < 4; ++i) p[i] = uint8_t(v >> (8 * i));
}

constexpr uint32_t kMantissaMask = 0x7FF;
constexpr int kImagShift = 6, kImagSign = 17, kRealShift = 18, kRealSign = 29;
constexpr int kMaxMantissa = 2047, kMinExponent = -32, kMaxExponent = 31;

bool isTwoByteMagic(const uint8_t* p)
{
    return p[0] == 0x11 && p[1] == 0x11;
}
bool isFourByteMagic(const uint8_t* p)
{
    return isTwoByteMagic(p) && p[2] == 0x11 && p[3] == 0x11;
}
}  // namespace

const char* toString(Chip c)
{
    switch (c)
    {
        case Chip::BCM4366c0:
            return "bcm4366c0";
        case Chip::BCM43455c0:
            return "bcm43455c0";
        case Chip::BCM4358:
            return "bcm4358";
        case Chip::BCM4339:
            return "bcm4339";
    }
    return "?";
}

bool chipFromWord(uint16_t word, Chip& out)
{
    switch (word)
    {
        case kChip4366c0:
            out = Chip::BCM4366c0;
            return true;
        case kChip43455c0:
            out = Chip::BCM43455c0;
            return true;
        case kChip4358:
        case kChip4358Example:
            out = Chip::BCM4358;
            return true;
        case kChip4339:
            out = Chip::BCM4339;
            return true;
        default:
            return false;
    }
}

unsigned chipCores(Chip c)
{
    switch (c)
    {
        case Chip::BCM4366c0:
            return 4;
        case Chip::BCM4358:
            return 2;
        case Chip::BCM43455c0:
        case Chip::BCM4339:
            return 1;
    }
    return 0;
}

bool chipSupportsBandwidth(Chip c, unsigned bandwidthMHz)
{
    // nexmon_csi: "up to 80 MHz bandwidth" on all four chips; the 2.4 GHz band at 20/40. The
    // BCM4366c0 radio also does 160 MHz (chanspec code 5, 512 words per report); nexmon_csi
    // does not document it, so 160 MHz is decoded for the 4366c0 only, from firmware that
    // reports it (and from the emulator / simulator).
    if (bandwidthMHz == 160) return c == Chip::BCM4366c0;
    return bandwidthMHz == 20 || bandwidthMHz == 40 || bandwidthMHz == 80;
}

const char* toString(RejectReason r)
{
    switch (r)
    {
        case RejectReason::TooShort:
            return "too short";
        case RejectReason::BadMagic:
            return "wrong magic";
        case RejectReason::UnknownChip:
            return "unknown chip";
        case RejectReason::BadChanspec:
            return "bad chanspec";
        case RejectReason::SizeMismatch:
            return "size not matching bandwidth";
        case RejectReason::BadCoreStream:
            return "impossible core/stream";
        case RejectReason::Count:
            break;
    }
    return "?";
}

const char* toString(FormatHint f)
{
    switch (f)
    {
        case FormatHint::Auto:
            return "auto";
        case FormatHint::Nexmon:
            return "nexmon";
        case FormatHint::NexmonLegacy:
            return "nexmon-legacy";
        case FormatHint::UbiLocate:
            return "ubilocate";
    }
    return "?";
}

FormatHint formatHintFromString(const std::string& s)
{
    for (auto f :
         {FormatHint::Auto, FormatHint::Nexmon, FormatHint::NexmonLegacy, FormatHint::UbiLocate})
        if (s == toString(f)) return f;
    throw std::invalid_argument(
        "unknown Nexmon format '" + s + "' (expected auto, nexmon, nexmon-legacy or ubilocate)");
}

size_t datagramSize(NexmonHeaderVariant v, unsigned nfft)
{
    return kHeaderBytes + 4 * size_t(nfft) +
           (v == NexmonHeaderVariant::UbiLocate ? kUbiLocateTrailerBytes : 0);
}

bool parseHeader(
    const uint8_t* data, size_t len, FormatHint hint, DatagramHeader& h, RejectReason& why)
{
    if (len < kHeaderBytes)
    {
        why = RejectReason::TooShort;
        return false;
    }
    if (!isTwoByteMagic(data))
    {
        why = RejectReason::BadMagic;
        return false;
    }
    const auto chanspec = Chanspec::decode(readLE16(data + 14));
    if (!chanspec)
    {
        why = RejectReason::BadChanspec;
        return false;
    }
    const unsigned nfft = chanspec->nfft();

    // All three variants share offsets 4..17; they differ in bytes 0..3 and in the trailer.
    NexmonHeaderVariant variant;
    switch (hint)
    {
        case FormatHint::Nexmon:
            variant = NexmonHeaderVariant::Nexmon;
            break;
        case FormatHint::NexmonLegacy:
            variant = NexmonHeaderVariant::NexmonLegacy;
            break;
        case FormatHint::UbiLocate:
            variant = NexmonHeaderVariant::UbiLocate;
            break;
        case FormatHint::Auto:
        default:
            if (isFourByteMagic(data))
                variant = NexmonHeaderVariant::NexmonLegacy;
            else if (len == datagramSize(NexmonHeaderVariant::UbiLocate, nfft))
                variant = NexmonHeaderVariant::UbiLocate;
            else
                variant = NexmonHeaderVariant::Nexmon;
            break;
    }
    if (variant == NexmonHeaderVariant::NexmonLegacy && !isFourByteMagic(data))
    {
        why = RejectReason::BadMagic;
        return false;
    }
    if (len != datagramSize(variant, nfft))
    {
        why = RejectReason::SizeMismatch;
        return false;
    }

    h = DatagramHeader{};
    h.variant = variant;
    h.chanspec = *chanspec;
    std::memcpy(h.transmitter.bytes.data(), data + 4, 6);
    h.sequenceControl = readLE16(data + 10);
    const uint16_t csiconf = readLE16(data + 12);
    const uint16_t word16 = readLE16(data + 16);
    if (variant == NexmonHeaderVariant::UbiLocate)
    {
        h.coreMask = data[2];
        h.streamMask = data[3];
        h.core = uint8_t((csiconf & 0xFF) >> 2);
        h.stream = uint8_t(csiconf & 0x3);
        h.firmwareCounter = word16;
    }
    else
    {
        if (!chipFromWord(word16, h.chip))
        {
            why = RejectReason::UnknownChip;
            return false;
        }
        h.chipId = word16;
        if (!chipSupportsBandwidth(h.chip, chanspec->bandwidthMHz))
        {
            why = RejectReason::BadChanspec;
            return false;
        }
        if (h.chip == Chip::BCM4366c0)
        {
            // 4366c0: core in bits 8–10, stream in bits 11–13.
            h.core = uint8_t((csiconf >> 8) & 0x7);
            h.stream = uint8_t((csiconf >> 11) & 0x7);
        }
        else
        {
            // The other chips: core in bits 0–2, stream in bits 3–5 (nexmon_csi README).
            h.core = uint8_t(csiconf & 0x7);
            h.stream = uint8_t((csiconf >> 3) & 0x7);
        }
        if (variant == NexmonHeaderVariant::Nexmon)
        {
            h.rssi_dBm = int8_t(data[2]);
            h.frameControl = data[3];
        }
    }
    const bool coreOk = h.core < chipCores(h.chip) && (!h.coreMask || ((h.coreMask >> h.core) & 1));
    const bool streamOk =
        h.stream < kMaxStreams && (!h.streamMask || ((h.streamMask >> h.stream) & 1));
    if (!coreOk || !streamOk)
    {
        why = RejectReason::BadCoreStream;
        return false;
    }
    return true;
}

uint32_t packWord(std::complex<float> v)
{
    // Bit arithmetic instead of ilogb/ldexp/lround: the emulator and the simulator's pcap
    // output pack millions of words a second.
    const float re = std::abs(v.real()), im = std::abs(v.imag());
    const float largest = std::max(re, im);
    if (!(largest > 0.0f) || !std::isfinite(largest)) return 0;
    uint32_t bits;
    std::memcpy(&bits, &largest, 4);
    const int biased = int(bits >> 23);  // sign is 0
    // floor(log2(largest)) for normal floats; subnormals are far below 2^-32 · 2^-10 anyway.
    int e = std::clamp(biased - 127 - 10, kMinExponent, kMaxExponent);
    const auto scaleFor = [](int exponent)
    {
        const uint32_t b = uint32_t(127 - exponent) << 23;  // 2^-exponent, exponent in [-32, 31]
        float f;
        std::memcpy(&f, &b, 4);
        return f;
    };
    float scale = scaleFor(e);
    if (largest * scale + 0.5f >= 2048.0f && e < kMaxExponent) scale = scaleFor(++e);
    const auto mantissa = [](float x)
    { return uint32_t(std::min(x + 0.5f, float(kMaxMantissa))); };  // x ≥ 0: round half up
    const uint32_t mr = mantissa(re * scale), mi = mantissa(im * scale);
    uint32_t w = uint32_t(e) & 0x3F;
    w |= mi << kImagShift;
    w |= mr << kRealShift;
    if (v.imag() < 0 && mi) w |= 1u << kImagSign;
    if (v.real() < 0 && mr) w |= 1u << kRealSign;
    return w;
}

namespace
{
/** Decodes n consecutive words into interleaved re/im floats. Branch-free and table-free
 * (the 2^e scale is built from the exponent bits) so the compiler vectorises it. */
inline void decodeRun(const uint8_t* words, unsigned n, float* reIm)
{
    for (unsigned i = 0; i < n; ++i)
    {
        uint32_t w;
        std::memcpy(&w, words + 4 * i, 4);                // little-endian host (x86-64, aarch64)
        const int32_t exponent = int32_t(w << 26) >> 26;  // sign-extend the 6-bit field
        const uint32_t scaleBits = uint32_t(exponent + 127) << 23;
        float scale;
        std::memcpy(&scale, &scaleBits, 4);
        const int32_t mi = int32_t((w >> kImagShift) & kMantissaMask);
        const int32_t mr = int32_t((w >> kRealShift) & kMantissaMask);
        const int32_t si = -int32_t((w >> kImagSign) & 1u), sr = -int32_t((w >> kRealSign) & 1u);
        reIm[2 * i] = float((mr ^ sr) - sr) * scale;
        reIm[2 * i + 1] = float((mi ^ si) - si) * scale;
    }
}
}  // namespace

std::complex<float> unpackWord(uint32_t w)
{
    uint8_t bytes[4];
    std::memcpy(bytes, &w, 4);
    float reIm[2];
    decodeRun(bytes, 1, reIm);
    return {reIm[0], reIm[1]};
}

std::complex<float> unpackWord4358(uint32_t w)
{
    // nexmon_csi unpack_float format 0: nman = 9 (8-bit magnitude + sign), nexp = 5.
    const int exponent = int32_t(w << 27) >> 27;
    const float scale = std::ldexp(1.0f, exponent);
    const int mi = int((w >> 5) & 0xFF), mr = int((w >> 14) & 0xFF);
    const float re = float((w >> 22) & 1u ? -mr : mr) * scale;
    const float im = float((w >> 13) & 1u ? -mi : mi) * scale;
    return {re, im};
}

void decodeWords(Chip chip, const uint8_t* words, unsigned nfft, std::complex<float>* out)
{
    if (chip == Chip::BCM4366c0)
    {
        decodeWords(words, nfft, out);
        return;
    }
    const unsigned half = nfft / 2;
    for (unsigned i = 0; i < nfft; ++i)
    {
        const uint8_t* p = words + 4 * i;
        std::complex<float> v;
        if (chip == Chip::BCM4358)
            v = unpackWord4358(
                uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24);
        else
            v = {float(int16_t(readLE16(p))), float(int16_t(readLE16(p + 2)))};
        out[(i + half) & (nfft - 1)] = v;
    }
}

void decodeWords(const uint8_t* words, unsigned nfft, std::complex<float>* out)
{
    static_assert(sizeof(std::complex<float>) == 2 * sizeof(float));
    // fftshift: raw words [0, N/2) are k = 0..N/2-1 (bins N/2..N-1), [N/2, N) are k < 0.
    const unsigned half = nfft / 2;
    auto* reIm = reinterpret_cast<float*>(out);
    decodeRun(words, half, reIm + 2 * half);
    decodeRun(words + 4 * half, half, reIm);
}

void encodeDatagram(
    const DatagramHeader& h, const std::complex<float>* subcarrierOrder, std::vector<uint8_t>& out)
{
    const unsigned nfft = h.nfft();
    out.assign(datagramSize(h.variant, nfft), 0);
    uint8_t* p = out.data();
    p[0] = p[1] = 0x11;
    uint16_t csiconf = 0, word16 = 0;
    switch (h.variant)
    {
        case NexmonHeaderVariant::Nexmon:
        case NexmonHeaderVariant::NexmonLegacy:
            if (h.variant == NexmonHeaderVariant::Nexmon)
                p[2] = uint8_t(h.rssi_dBm), p[3] = h.frameControl;
            else
                p[2] = p[3] = 0x11;
            // 4366c0: core in bits 8–10, stream in 11–13; the other chips: bits 0–2, 3–5.
            csiconf = h.chip == Chip::BCM4366c0 ? uint16_t((h.core & 7) << 8 | (h.stream & 7) << 11)
                                                : uint16_t((h.core & 7) | (h.stream & 7) << 3);
            word16 = h.chipId;
            break;
        case NexmonHeaderVariant::UbiLocate:
            p[2] = h.coreMask;
            p[3] = h.streamMask;
            csiconf = uint16_t((h.core << 2) | (h.stream & 3));
            word16 = h.firmwareCounter;
            break;
    }
    std::memcpy(p + 4, h.transmitter.bytes.data(), 6);
    writeLE16(p + 10, h.sequenceControl);
    writeLE16(p + 12, csiconf);
    writeLE16(p + 14, h.chanspec.raw);
    writeLE16(p + 16, word16);
    const unsigned half = nfft / 2;
    const bool int16Words = h.variant != NexmonHeaderVariant::UbiLocate &&
                            (h.chip == Chip::BCM43455c0 || h.chip == Chip::BCM4339);
    if (h.variant != NexmonHeaderVariant::UbiLocate && h.chip == Chip::BCM4358)
        throw std::invalid_argument("encodeDatagram: bcm4358 packed words are decode-only");
    const auto int16Of = [](float x)
    { return uint16_t(int16_t(std::lround(std::clamp(x, -32768.0f, 32767.0f)))); };
    for (unsigned i = 0; i < nfft; ++i)
    {
        const std::complex<float> v = subcarrierOrder[(i + half) & (nfft - 1)];
        uint8_t* w = p + kHeaderBytes + 4 * i;
        if (int16Words)
        {
            // int16 I (low half-word) and Q, rounded and saturated.
            writeLE16(w, int16Of(v.real()));
            writeLE16(w + 2, int16Of(v.imag()));
        }
        else
            writeLE32(w, packWord(v));
    }
}

DatagramHeader headerFor(const CObservationWiFiCSI& obs, unsigned tx, unsigned rx, Chip chip)
{
    DatagramHeader h;
    h.variant = obs.headerVariant;
    h.rssi_dBm = obs.rssi_dBm;
    h.frameControl = obs.frameControl;
    h.transmitter = obs.transmitter;
    h.sequenceControl = uint16_t(obs.sequenceNumber << 4 | (obs.fragmentNumber & 0xF));
    h.core = uint8_t(obs.coreOfRow(rx));  // the row's own core (rxCores: a core subset)
    h.stream = uint8_t(tx);
    h.chanspec = obs.chanspec;
    h.chip = obs.headerVariant == NexmonHeaderVariant::UbiLocate ? Chip::BCM4366c0 : chip;
    h.chipId = obs.headerVariant == NexmonHeaderVariant::UbiLocate ? 0 : chipWord(h.chip);
    h.firmwareCounter = obs.firmwareCounter;
    if (obs.headerVariant == NexmonHeaderVariant::UbiLocate)
    {
        for (unsigned r = 0; r < obs.nRx; ++r) h.coreMask |= uint8_t(1u << obs.coreOfRow(r));
        h.streamMask = uint8_t((1u << obs.nTx) - 1);
    }
    return h;
}

uint16_t chipWord(Chip c)
{
    switch (c)
    {
        case Chip::BCM4366c0:
            return kChip4366c0;
        case Chip::BCM43455c0:
            return kChip43455c0;
        case Chip::BCM4358:
            return kChip4358;
        case Chip::BCM4339:
            return kChip4339;
    }
    return kChip4366c0;
}

std::vector<std::vector<uint8_t>> encodeFrame(const CObservationWiFiCSI& obs, Chip chip)
{
    std::vector<std::vector<uint8_t>> datagrams;
    for (unsigned rx = 0; rx < obs.nRx; ++rx)
        for (unsigned tx = 0; tx < obs.nTx; ++tx)
        {
            if (!obs.isPresent(tx, rx)) continue;
            datagrams.emplace_back();
            encodeDatagram(headerFor(obs, tx, rx, chip), obs.pair(tx, rx), datagrams.back());
        }
    return datagrams;
}

}  // namespace mrpt_wifi::nexmon
