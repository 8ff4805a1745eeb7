/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/Clock.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sensor/AtherosCsiFormat.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>

#include <cstring>

namespace mrpt_wifi::atheros
{
namespace
{
constexpr unsigned kBitsPerValue = 10;

uint16_t readLE16(const uint8_t* p)
{
    return uint16_t(p[0] | (p[1] << 8));
}

/** Channel number of a 2.4 / 5 GHz centre frequency; 0 if none. */
unsigned channelOf(unsigned mhz)
{
    if (mhz == 2484) return 14;
    if (mhz >= 2412 && mhz <= 2472 && (mhz - 2407) % 5 == 0) return (mhz - 2407) / 5;
    if (mhz >= 5035 && mhz <= 5980 && mhz % 5 == 0) return (mhz - 5000) / 5;
    return 0;
}
}  // namespace

const std::vector<int>& toneSubcarriers(unsigned tones)
{
    static const std::vector<int> ht20 = []
    {
        std::vector<int> v;
        for (int k = -28; k <= 28; ++k)
            if (k) v.push_back(k);
        return v;
    }();
    static const std::vector<int> ht40 = []
    {
        std::vector<int> v;
        for (int k = -58; k <= 58; ++k)
            if (std::abs(k) >= 2) v.push_back(k);
        return v;
    }();
    if (tones == 56) return ht20;
    if (tones == 114) return ht40;
    throw std::invalid_argument("Atheros CSI: " + std::to_string(tones) + " tones (56 or 114)");
}

bool parseRecord(
    const uint8_t* d, size_t length, AtherosRecord& r, std::string& why, std::string* reason)
{
    const auto fail = [&](const char* category, std::string text)
    {
        if (reason) *reason = category;
        why = std::move(text);
        return false;
    };
    if (length < kStatusBytes)
        return fail(
            "record shorter than the 25-byte status",
            "record of " + std::to_string(length) + " bytes");
    r = AtherosRecord{};
    for (int i = 7; i >= 0; --i) r.timestamp = (r.timestamp << 8) | d[i];
    r.csiLen = readLE16(d + 8);
    r.channel_MHz = readLE16(d + 10);
    r.phyError = d[12];
    r.noiseFloor = d[13];
    r.rate = d[14];
    r.bandwidth = d[15];
    r.tones = d[16];
    r.nr = d[17];
    r.nc = d[18];
    r.rssi = d[19];
    std::memcpy(r.chainRssi, d + 20, 3);
    r.payloadLen = readLE16(d + 23);
    if (kStatusBytes + size_t(r.csiLen) + r.payloadLen != length)
        return fail(
            "sizes don't add up to the record length (a big-endian log, or not an Atheros CSI "
            "Tool log?)",
            "25 + csi_len " + std::to_string(r.csiLen) + " + payload_len " +
                std::to_string(r.payloadLen) + " != record length " + std::to_string(length));
    if (r.csiLen == 0) return true;  // a frame without CSI
    if (r.nr < 1 || r.nr > kMaxAntennas || r.nc < 1 || r.nc > kMaxAntennas)
        return fail(
            "impossible antenna counts",
            "nr=" + std::to_string(r.nr) + " nc=" + std::to_string(r.nc) + " (1–3)");
    if (r.tones != 56 && r.tones != 114)
        return fail("impossible number of tones", std::to_string(r.tones) + " tones (56 or 114)");
    const size_t values = size_t(r.nr) * r.nc * r.tones * 2;
    if (r.csiLen * 8u != values * kBitsPerValue)
        return fail(
            "csi_len disagrees with the antenna and tone counts",
            "csi_len " + std::to_string(r.csiLen) + " bytes where nr=" + std::to_string(r.nr) +
                " nc=" + std::to_string(r.nc) + " tones=" + std::to_string(r.tones) + " need " +
                std::to_string(values * kBitsPerValue / 8));
    // 10-bit two's-complement values, least significant bit first.
    const uint8_t* bits = d + kStatusBytes;
    const auto value = [&](size_t index)
    {
        const size_t bit = index * kBitsPerValue, byte = bit / 8;
        uint32_t w = bits[byte];
        if (byte + 1 < r.csiLen) w |= uint32_t(bits[byte + 1]) << 8;
        const int v = int((w >> (bit % 8)) & ((1u << kBitsPerValue) - 1));
        return float(v >= 512 ? v - 1024 : v);
    };
    r.csi.resize(values / 2);
    for (size_t i = 0; i < r.csi.size(); ++i) r.csi[i] = {value(2 * i + 1), value(2 * i)};
    return true;
}

bool toObservation(const AtherosRecord& r, CObservationWiFiCSI& obs, std::string& why)
{
    const unsigned primary = channelOf(r.channel_MHz);
    const bool ht40 = r.tones == 114;
    try
    {
        // The log names the primary channel only: at 40 MHz the secondary is assumed above.
        obs.chanspec = ht40 ? Chanspec::make(primary + 2, 40, 0) : Chanspec::make(primary, 20);
    }
    catch (const std::exception&)
    {
        why = "channel frequency " + std::to_string(r.channel_MHz) + " MHz is no " +
              (ht40 ? "40" : "20") + " MHz WiFi channel";
        return false;
    }
    obs.source = "ar9300";
    obs.rssi_dBm = 0;  // the tool's RSSI is relative (dB above the noise floor), not dBm
    obs.antennaRssi_dB.assign(r.chainRssi, r.chainRssi + r.nr);
    if (r.noiseFloor) obs.noiseFloor_dBm = float(int8_t(r.noiseFloor));
    obs.resize(r.nc, r.nr, obs.chanspec.nfft());
    const auto& ks = toneSubcarriers(r.tones);
    for (unsigned c = 0; c < r.nc; ++c)
        for (unsigned a = 0; a < r.nr; ++a)
        {
            for (unsigned t = 0; t < r.tones; ++t)
                obs.at(c, a, subcarrierToBin(ks[t], obs.nfft())) = r.at(a, c, t);
            obs.setPresent(c, a);
        }
    obs.subcarrierIndices.assign(ks.begin(), ks.end());
    return true;
}

namespace
{
class AtherosCsiDecoder : public CsiDecoder
{
public:
    std::string name() const override { return "atheros"; }
    std::string description() const override
    {
        return "Atheros CSI Tool log (ath9k AR93xx, little-endian, as its read_log_file reads "
               "it): 56 / 114 tones, up to 3x3, 20/40 MHz";
    }
    int probe(const uint8_t* head, size_t len) const override
    {
        // No magic number: the first record's sizes must add up and its fields be plausible.
        if (len < 2 + kStatusBytes) return 0;
        const size_t length = readLE16(head);
        const uint8_t* d = head + 2;
        const size_t csiLen = readLE16(d + 8), payloadLen = readLE16(d + 23);
        if (length != kStatusBytes + csiLen + payloadLen || csiLen == 0) return 0;
        const unsigned nr = d[17], nc = d[18], tones = d[16];
        if (nr < 1 || nr > kMaxAntennas || nc < 1 || nc > kMaxAntennas) return 0;
        if (tones != 56 && tones != 114) return 0;
        if (csiLen * 8 != size_t(nr) * nc * tones * 2 * kBitsPerValue) return 0;
        if (!channelOf(readLE16(d + 10))) return 0;
        return 80;
    }
    void decodeFile(
        const std::string& path, const CsiDecodeOptions& options, const CsiFrameSink& onFrame,
        const CsiProgress& onProgress, CsiDecodeSummary& summary) const override
    {
        const auto bytes = readWholeFile(path);
        ProgressThrottle progress(onProgress);
        summary.notes.push_back(
            "Atheros tones taken in ascending subcarrier order (HT20 -28..-1, 1..28; HT40 "
            "-58..-2, 2..58); 40 MHz: secondary channel assumed above the logged one");
        size_t pos = 0;
        while (pos < bytes.size())
        {
            const bool lengthFits = pos + 2 <= bytes.size();
            const size_t length = lengthFits ? readLE16(bytes.data() + pos) : 0;
            if (!lengthFits || pos + 2 + length > bytes.size())
            {
                if (summary.records == 0)
                    throw CsiDecodeError(
                        path, pos, name(),
                        "the first record does not fit in the file (not an Atheros CSI Tool log, "
                        "or cut inside its first record)");
                summary.noteOnce(
                    "the last record (byte " + std::to_string(pos) + ") is truncated: " +
                    (!lengthFits ? std::string("1 byte of its length")
                                 : std::to_string(length) + " bytes announced, " +
                                       std::to_string(bytes.size() - pos - 2)) +
                    " in the file (a capture that was stopped?); ignored");
                break;
            }
            ++summary.records;
            const size_t start = pos;
            AtherosRecord r;
            std::string why, reason;
            pos += 2 + length;
            progress.update(pos, bytes.size());
            if (!parseRecord(bytes.data() + start + 2, length, r, why, &reason))
            {
                rejectRecord(path, name(), options, summary, start, reason, why);
                continue;
            }
            if (r.csiLen == 0)
            {
                ++summary.skipped;
                continue;
            }
            auto obs = CObservationWiFiCSI::Create();
            if (!toObservation(r, *obs, why))
            {
                rejectRecord(path, name(), options, summary, start, "no WiFi channel", why);
                continue;
            }
            obs->sensorLabel = options.assembler.sensorLabel;
            obs->sensorPose = options.assembler.sensorPose;
            obs->routerAddress = "file";
            // The NIC's TSF [µs], not wall time.
            obs->timestamp = mrpt::Clock::fromDouble(double(r.timestamp) * 1e-6);
            ++summary.frames;
            onFrame(std::move(obs));
        }
        progress.update(1, 1);
    }
};
}  // namespace
}  // namespace mrpt_wifi::atheros

using mrpt_wifi::atheros::AtherosCsiDecoder;
MRPT_WIFI_REGISTER_CSI_DECODER(AtherosCsiDecoder)
