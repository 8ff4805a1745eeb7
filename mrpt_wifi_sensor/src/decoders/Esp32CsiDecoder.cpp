/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/Clock.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>
#include <mrpt_wifi/sensor/Esp32CsiFormat.h>

#include <algorithm>
#include <charconv>
#include <cstring>
#include <iterator>

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

bool parseLine(std::string_view line, Esp32Line& l, std::string& why, std::string* reason)
{
    l = Esp32Line{};
    const auto fail = [&](const std::string& cat, std::string text)
    {
        if (reason) *reason = cat;
        why = std::move(text);
        return false;
    };
    const size_t open = line.find('[');
    const size_t close = line.find(']', open == std::string_view::npos ? 0 : open);
    if (!isCsiLine(line) || open == std::string_view::npos || close == std::string_view::npos)
        return fail(
            "no [..] buffer (truncated line?)",
            "not a CSI_DATA line with a [..] buffer (truncated?)");
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
            return fail(
                "unknown CSI_DATA layout",
                std::to_string(f.size()) + " metadata fields (known: 14, 24, 25)");
    }
    const auto field = [&](unsigned i, auto& v, const char* what)
    {
        if (toNumber(f[i], v)) return true;
        return fail(
            std::string("field ") + what + " is not a number",
            std::string("field ") + std::to_string(i) + " (" + what + ") '" + std::string(f[i]) +
                "' is not a number");
    };
    if (iSeq >= 0 && !field(unsigned(iSeq), l.seq, "seq")) return false;
    if (const auto mac = MacAddress::parse(f[iMac]))
        l.mac = *mac;
    else
        return fail(
            "field mac is not a MAC address",
            "field 2 '" + std::string(f[iMac]) + "' is not a MAC address");
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
    if (l.metadataFields != 14)
    {
        // sig_mode, cwb and stbc sit at 5, 7 and 11 in both the esp-csi and the
        // ESP32-CSI-Tool layouts; first_word_invalid only in esp-csi's (the last field).
        unsigned fwi = 0;
        if (!field(5, l.sigMode, "sig_mode") || !field(7, l.cwb, "cwb") ||
            !field(11, l.stbc, "stbc") ||
            (l.metadataFields == 24 && !field(23, fwi, "first_word_invalid")))
            return false;
        l.hasPacketInfo = true;
        l.firstWordInvalid = fwi != 0;
        // ESP32-CSI-Tool's rows don't carry first_word_invalid; the ESP32 reports it set (its
        // first four buffer bytes are not CSI: constant across rows in the tool's samples).
        l.firstWordAssumed = l.metadataFields == 25;
        if (l.firstWordAssumed) l.firstWordInvalid = true;
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
            return fail(
                "a CSI value is not an int8",
                "CSI value '" + std::string(data.substr(0, end)) + "' is not an int8");
        l.values.push_back(int8_t(v));
        if (end == std::string_view::npos) break;
        data.remove_prefix(end);
    }
    if (l.values.size() < l.len && l.values.size() == kLltfValues)
        l.shorterThanAnnounced = true;  // the L-LTF alone (ESP32-CSI-Tool)
    else if (l.values.size() != l.len)
        return fail(
            "len disagrees with the values in the buffer", "len says " + std::to_string(l.len) +
                                                               " values, the buffer has " +
                                                               std::to_string(l.values.size()));
    return true;
}

const char* toString(LtfBlock::Kind k)
{
    switch (k)
    {
        case LtfBlock::Kind::LLTF:
            return "L-LTF";
        case LtfBlock::Kind::HTLTF:
            return "HT-LTF";
        case LtfBlock::Kind::STBC_HTLTF:
            return "STBC-HT-LTF";
    }
    return "?";
}

namespace
{
std::vector<int> span(int from, int to)
{
    std::vector<int> v;
    for (int k = from; k <= to; ++k) v.push_back(k);
    return v;
}
std::vector<int> concat(std::vector<int> a, const std::vector<int>& b)
{
    a.insert(a.end(), b.begin(), b.end());
    return a;
}
/** ±lo..±hi around `centre`, ascending. */
std::vector<int> bandAround(int centre, int lo, int hi)
{
    std::vector<int> v;
    for (int k = -hi; k <= hi; ++k)
        if (std::abs(k) >= lo) v.push_back(centre + k);
    return v;
}
}  // namespace

BufferLayout bufferLayout(const Esp32Line& l)
{
    // wifi_second_chan_t: 0 none, 1 above, 2 below. With a secondary channel the fields are
    // indexed on the 40 MHz FFT; the primary 20 MHz is its upper half (below) or lower half.
    BufferLayout out;
    const int secondary = l.secondaryChannel;
    const bool none = secondary != 1 && secondary != 2;
    out.bandwidthMHz = none ? 20 : 40;
    out.primaryOffset = none ? 0 : secondary == 2 ? 32 : -32;
    const std::vector<int> fft64 = concat(span(0, 31), span(-32, -1));
    const std::vector<int> lltf = none ? fft64 : secondary == 2 ? span(0, 63) : span(-64, -1);

    std::vector<std::pair<LtfBlock::Kind, std::vector<int>>> fields = {
        {LtfBlock::Kind::LLTF, lltf}};
    const bool ht = l.hasPacketInfo && l.sigMode == 1;
    if (ht)
    {
        std::vector<int> htltf;
        const bool stbc = l.stbc != 0;
        if (none)
            htltf = fft64;
        else if (l.cwb == 1)
            htltf = stbc ? concat(span(0, 60), span(-60, -1)) : concat(span(0, 63), span(-64, -1));
        else if (secondary == 2)
            htltf = stbc ? span(0, 62) : span(0, 63);
        else
            htltf = stbc ? span(-62, -1) : span(-64, -1);
        fields.push_back({LtfBlock::Kind::HTLTF, htltf});
        if (stbc) fields.push_back({LtfBlock::Kind::STBC_HTLTF, htltf});
    }
    size_t entries = 0;
    for (const auto& f : fields) entries += f.second.size();
    out.matchedTable = l.hasPacketInfo && (l.sigMode == 0 || ht) && 2 * entries == l.values.size();
    if (!out.matchedTable) fields.resize(1);  // the L-LTF leads whenever it is enabled

    const bool ht40 = !none && l.cwb == 1;
    size_t first = 0;
    for (auto& [kind, ks] : fields)
    {
        LtfBlock b;
        b.kind = kind;
        b.firstEntry = first;
        b.k = ks;
        first += ks.size();
        const std::vector<int> band = kind == LtfBlock::Kind::LLTF
                                          ? bandAround(out.primaryOffset, 1, 26)
                                      : ht40 ? bandAround(0, 2, 58)
                                             : bandAround(out.primaryOffset, 1, 28);
        for (int k : band)
            if (std::find(ks.begin(), ks.end(), k) != ks.end()) b.measured.push_back(k);
        out.blocks.push_back(std::move(b));
    }
    return out;
}

const std::vector<int>& lltfSubcarriers()
{
    static const std::vector<int> ks = bandAround(0, 1, 26);
    return ks;
}

bool toObservation(
    const Esp32Line& l, CObservationWiFiCSI& obs, std::string& why, bool legacyLtfOnly)
{
    if (l.values.size() < kLltfValues)
    {
        why = "buffer of " + std::to_string(l.values.size()) + " values, shorter than the L-LTF (" +
              std::to_string(kLltfValues) + ")";
        return false;
    }
    const BufferLayout layout = bufferLayout(l);
    try
    {
        if (layout.bandwidthMHz == 20)
            obs.chanspec = Chanspec::make(l.channel, 20);
        else  // centre 2 channel numbers towards the secondary; sideband of the primary
            obs.chanspec = Chanspec::make(
                unsigned(int(l.channel) + (layout.primaryOffset > 0 ? -2 : 2)), 40,
                layout.primaryOffset > 0 ? 1 : 0);
    }
    catch (const std::exception&)
    {
        why = "channel " + std::to_string(l.channel) + " (secondary " +
              std::to_string(l.secondaryChannel) + ") does not exist";
        return false;
    }
    // The HT-LTF (and STBC's second one) when the line has them, else the L-LTF.
    std::vector<const LtfBlock*> used;
    for (const auto& b : layout.blocks)
        if (b.kind != LtfBlock::Kind::LLTF && !legacyLtfOnly) used.push_back(&b);
    if (used.empty()) used.push_back(&layout.blocks.front());

    obs.source = "esp32";
    obs.transmitter = l.mac;
    obs.rssi_dBm = int8_t(std::clamp(l.rssi, -128, 127));
    obs.antennaRssi_dB = {float(l.rssi)};
    obs.noiseFloor_dBm = float(l.noiseFloor);
    if (l.hasAgc) obs.agc_dB = float(l.agcGain);
    obs.firmwareCounter = uint16_t(l.seq);
    const unsigned nfft = obs.chanspec.nfft();
    obs.resize(unsigned(used.size()), 1, nfft);
    obs.maskedBins.clear();
    std::vector<int> measured = used.front()->measured;
    for (unsigned m = 0; m < used.size(); ++m)
    {
        const LtfBlock& b = *used[m];
        for (size_t i = 0; i < b.k.size(); ++i)
        {
            const size_t e = b.firstEntry + i;
            obs.at(m, 0, subcarrierToBin(b.k[i], nfft)) = {
                float(l.values[2 * e + 1]), float(l.values[2 * e])};
        }
        std::vector<int> both;
        std::set_intersection(
            measured.begin(), measured.end(), b.measured.begin(), b.measured.end(),
            std::back_inserter(both));
        measured.swap(both);
        obs.setPresent(m, 0);
    }
    // ESP-IDF: with first_word_invalid the buffer's first four bytes (two entries, in the
    // leading L-LTF) are not CSI: kept as reported, but masked and not listed as measured.
    if (l.firstWordInvalid && used.front()->firstEntry == 0)
        for (size_t e = 0; e < 2; ++e)
        {
            const int k = used.front()->k[e];
            const auto it = std::find(measured.begin(), measured.end(), k);
            if (it == measured.end()) continue;
            measured.erase(it);
            obs.maskedBins.push_back(uint16_t(subcarrierToBin(k, nfft)));
        }
    std::sort(obs.maskedBins.begin(), obs.maskedBins.end());
    obs.subcarrierIndices.assign(measured.begin(), measured.end());
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
        return "esp-csi CSI_DATA text lines (ESP32 serial log / .csv): 1 antenna; the HT-LTF "
               "(and STBC's second) when the line has one, else the L-LTF; 20 or 40 MHz";
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
        uint64_t stbcLines = 0, wideLines = 0, htLines = 0;
        std::string shorter;  // the note about rows shorter than their len, from the first
        bool firstWordAssumed = false;
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
                std::string why, reason;
                auto obs = CObservationWiFiCSI::Create();
                bool ok = parseLine(line, l, why, &reason);
                if (!ok && eol == text.size())
                {
                    // The last line, without its newline: a log cut off mid-line.
                    summary.noteOnce(
                        "the last line (" + std::to_string(lineNo) +
                        ") is cut off (a capture that was stopped?); ignored: " + why);
                    break;
                }
                if (ok && !(ok = toObservation(l, *obs, why, options.esp32LegacyLtf)))
                    reason = "no valid channel or buffer";
                if (!ok)
                {
                    rejectRecord(
                        path, name(), options, summary, pos, reason, why,
                        "line " + std::to_string(lineNo));
                    pos = eol + 1;
                    progress.update(pos, text.size());
                    continue;
                }
                if (l.shorterThanAnnounced && shorter.empty())
                    shorter = "rows whose len announces " + std::to_string(l.len) +
                              " values hold " + std::to_string(l.values.size()) +
                              " (first at line " + std::to_string(lineNo) +
                              ", as ESP32-CSI-Tool logs HT frames): read as the L-LTF only";
                firstWordAssumed |= l.firstWordAssumed;
                obs->sensorLabel = options.assembler.sensorLabel;
                obs->sensorPose = options.assembler.sensorPose;
                obs->routerAddress = "file";
                // The device's µs clock since boot, not wall time.
                obs->timestamp = mrpt::Clock::fromDouble(double(l.localTimestamp_us) * 1e-6);
                ++summary.frames;
                // More than the L-LTF's 52 subcarriers: an HT-LTF (56 or 114).
                htLines += obs->subcarrierIndices.size() > 52;
                stbcLines += obs->nTx > 1;
                wideLines += obs->chanspec.bandwidthMHz == 40;
                onFrame(std::move(obs));
            }
            else if (!line.empty() && line != "\r")
                ++summary.skipped;  // header row, boot messages, logs
            pos = eol + 1;
            progress.update(pos, text.size());
        }
        progress.update(1, 1);
        if (!shorter.empty()) summary.notes.push_back(shorter);
        if (firstWordAssumed)
            summary.notes.push_back(
                "ESP32-CSI-Tool rows don't say whether the buffer's first 4 bytes are CSI; the "
                "ESP32 reports them invalid (first_word_invalid): masked");
        summary.details += "esp32: " + std::to_string(htLines) + " frames from the HT-LTF (" +
                           std::to_string(stbcLines) + " with STBC: 2 space-time streams), " +
                           std::to_string(summary.frames - htLines) + " from the L-LTF" +
                           (options.esp32LegacyLtf ? " (--esp32-lltf)" : "") + "; " +
                           std::to_string(wideLines) + " on a 40 MHz channel";
    }
};
}  // namespace
}  // namespace mrpt_wifi::esp32

using mrpt_wifi::esp32::Esp32CsiDecoder;
MRPT_WIFI_REGISTER_CSI_DECODER(Esp32CsiDecoder)
