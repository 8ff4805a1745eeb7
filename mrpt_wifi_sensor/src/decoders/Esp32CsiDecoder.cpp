/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/Clock.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/Esp32CsiFormat.h>

#include <charconv>
#include <cstring>

namespace mrpt_wifi::esp32
{
namespace
{
constexpr std::string_view kTag = "CSI_DATA";
constexpr unsigned kLltfValues = 128;  //!< 64 subcarriers × (imag, real)

template <typename T>
bool toNumber(std::string_view s, T& out)
{
    while (!s.empty() && (s.front() == ' ' || s.front() == '"')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '"' || s.back() == '\r'))
        s.remove_suffix(1);
    if (s.empty()) return false;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}
}  // namespace

bool isCsiLine(std::string_view line)
{
    return line.substr(0, kTag.size()) == kTag;
}

bool parseLine(std::string_view line, Esp32Line& l, std::string& why)
{
    l = Esp32Line{};
    const size_t open = line.find('[');
    const size_t close = line.find(']', open == std::string_view::npos ? 0 : open);
    if (!isCsiLine(line) || open == std::string_view::npos || close == std::string_view::npos)
    {
        why = "not a CSI_DATA line with a [..] buffer (truncated?)";
        return false;
    }
    std::vector<std::string_view> f;
    std::string_view meta = line.substr(0, open);
    while (!meta.empty())
    {
        const size_t c = meta.find(',');
        f.push_back(meta.substr(0, c));
        if (c == std::string_view::npos) break;
        meta.remove_prefix(c + 1);
    }
    // The bracket follows the last comma (possibly after a quote): drop the empty last field.
    if (!f.empty() && (f.back().empty() || f.back() == "\"")) f.pop_back();
    l.metadataFields = unsigned(f.size());
    unsigned iMac = 2, iRssi = 3, iNoise = 14, iChannel = 16, iSecondary = 17, iTime = 18,
             iLen = 22;
    int iSeq = 1, iAgc = -1;
    switch (l.metadataFields)
    {
        case 24:
            break;
        case 25:
            iSeq = -1;
            iLen = 24;
            break;
        case 14:
            iNoise = 5;
            iAgc = 7;
            iChannel = 8;
            iSecondary = 0;
            iTime = 9;
            iLen = 12;
            break;
        default:
            why = "unknown CSI_DATA layout with " + std::to_string(f.size()) +
                  " metadata fields (known: 14, 24, 25)";
            return false;
    }
    const auto field = [&](unsigned i, auto& v, const char* what)
    {
        if (toNumber(f[i], v)) return true;
        why = std::string("field ") + std::to_string(i) + " (" + what + ") '" + std::string(f[i]) +
              "' is not a number";
        return false;
    };
    if (iSeq >= 0 && !field(unsigned(iSeq), l.seq, "seq")) return false;
    if (const auto mac = MacAddress::parse(f[iMac]))
        l.mac = *mac;
    else
    {
        why = "field 2 '" + std::string(f[iMac]) + "' is not a MAC address";
        return false;
    }
    if (!field(iRssi, l.rssi, "rssi") || !field(iNoise, l.noiseFloor, "noise_floor") ||
        !field(iChannel, l.channel, "channel") || !field(iTime, l.localTimestamp_us, "timestamp") ||
        !field(iLen, l.len, "len"))
        return false;
    if (iSecondary && !field(iSecondary, l.secondaryChannel, "secondary_channel")) return false;
    if (iAgc >= 0)
    {
        if (!field(unsigned(iAgc), l.agcGain, "agc_gain")) return false;
        l.hasAgc = true;
    }
    std::string_view data = line.substr(open + 1, close - open - 1);
    while (!data.empty())
    {
        const size_t start = data.find_first_not_of(" ,");
        if (start == std::string_view::npos) break;
        data.remove_prefix(start);
        const size_t end = data.find_first_of(" ,");
        int v = 0;
        if (!toNumber(data.substr(0, end), v) || v < -128 || v > 127)
        {
            why = "CSI value '" + std::string(data.substr(0, end)) + "' is not an int8";
            return false;
        }
        l.values.push_back(int8_t(v));
        if (end == std::string_view::npos) break;
        data.remove_prefix(end);
    }
    if (l.values.size() != l.len)
    {
        why = "len says " + std::to_string(l.len) + " values, the buffer has " +
              std::to_string(l.values.size()) + " (truncated line?)";
        return false;
    }
    return true;
}

const std::vector<int>& lltfSubcarriers()
{
    static const std::vector<int> ks = []
    {
        std::vector<int> v;
        for (int k = -26; k <= 26; ++k)
            if (k) v.push_back(k);
        return v;
    }();
    return ks;
}

bool toObservation(const Esp32Line& l, CObservationWiFiCSI& obs, std::string& why)
{
    if (l.values.size() < kLltfValues)
    {
        why = "buffer of " + std::to_string(l.values.size()) + " values, shorter than the L-LTF (" +
              std::to_string(kLltfValues) + ")";
        return false;
    }
    try
    {
        obs.chanspec = Chanspec::make(l.channel, 20);
    }
    catch (const std::exception&)
    {
        why = "channel " + std::to_string(l.channel) + " does not exist";
        return false;
    }
    obs.source = "esp32";
    obs.transmitter = l.mac;
    obs.rssi_dBm = int8_t(std::clamp(l.rssi, -128, 127));
    obs.antennaRssi_dB = {float(l.rssi)};
    obs.noiseFloor_dBm = float(l.noiseFloor);
    if (l.hasAgc) obs.agc_dB = float(l.agcGain);
    obs.firmwareCounter = uint16_t(l.seq);
    obs.resize(1, 1, 64);
    for (unsigned i = 0; i < 64; ++i)
        obs.at(0, 0, (i + 32) & 63) = {float(l.values[2 * i + 1]), float(l.values[2 * i])};
    const auto& ks = lltfSubcarriers();
    obs.subcarrierIndices.assign(ks.begin(), ks.end());
    obs.setPresent(0, 0);
    return true;
}

namespace
{
class Esp32CsiDecoder : public CsiDecoder
{
public:
    std::string name() const override { return "esp32"; }
    std::string description() const override
    {
        return "esp-csi CSI_DATA text lines (ESP32 serial log / .csv): 1 antenna, the L-LTF of "
               "the primary 20 MHz channel";
    }
    int probe(const uint8_t* head, size_t len) const override
    {
        const std::string_view s(reinterpret_cast<const char*>(head), len);
        for (size_t pos = 0; pos < s.size();)
        {
            const size_t eol = s.find('\n', pos);
            if (isCsiLine(s.substr(pos))) return 90;
            if (eol == std::string_view::npos) break;
            pos = eol + 1;
        }
        return 0;
    }
    void decodeFile(
        const std::string& path, const CsiDecodeOptions& options, const CsiFrameSink& onFrame,
        const CsiProgress& onProgress, CsiDecodeSummary& summary) const override
    {
        const auto bytes = readWholeFile(path);
        const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
        ProgressThrottle progress(onProgress);
        size_t pos = 0, lineNo = 0;
        while (pos < text.size())
        {
            size_t eol = text.find('\n', pos);
            if (eol == std::string_view::npos) eol = text.size();
            const auto line = text.substr(pos, eol - pos);
            ++lineNo;
            if (isCsiLine(line))
            {
                ++summary.records;
                Esp32Line l;
                std::string why;
                auto obs = CObservationWiFiCSI::Create();
                if (!parseLine(line, l, why) || !toObservation(l, *obs, why))
                    throw CsiDecodeError(
                        path, pos, name(), "line " + std::to_string(lineNo) + ": " + why);
                obs->sensorLabel = options.assembler.sensorLabel;
                obs->sensorPose = options.assembler.sensorPose;
                obs->routerAddress = "file";
                // The device's µs clock since boot, not wall time.
                obs->timestamp = mrpt::Clock::fromDouble(double(l.localTimestamp_us) * 1e-6);
                ++summary.frames;
                onFrame(std::move(obs));
            }
            else if (!line.empty() && line != "\r")
                ++summary.skipped;  // header row, boot messages, logs
            pos = eol + 1;
            progress.update(pos, text.size());
        }
        progress.update(1, 1);
    }
};
}  // namespace
}  // namespace mrpt_wifi::esp32

using mrpt_wifi::esp32::Esp32CsiDecoder;
MRPT_WIFI_REGISTER_CSI_DECODER(Esp32CsiDecoder)
