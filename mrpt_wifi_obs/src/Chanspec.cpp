/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/Chanspec.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace mrpt_wifi
{
namespace
{
constexpr uint16_t kBand2G = 0x0000, kBand5G = 0xC000, kBandMask = 0xC000;

unsigned bandwidthCode(unsigned mhz)
{
    switch (mhz)
    {
        case 20:
            return 2;
        case 40:
            return 3;
        case 80:
            return 4;
        case 160:
            return 5;
        default:
            return 0;
    }
}

/** Sidebands a bandwidth has: one per 20 MHz sub-channel. */
unsigned sidebandCount(unsigned mhz)
{
    return mhz / 20;
}

/** First 20 MHz channel of every 40 / 80 MHz block of the 5 GHz plan (802.11ac, incl. the
 * 165–177 extension). */
const std::vector<unsigned>& blockStarts(unsigned mhz)
{
    static const std::vector<unsigned> starts40 = {36,  44,  52,  60,  100, 108, 116,
                                                   124, 132, 140, 149, 157, 165, 173};
    static const std::vector<unsigned> starts80 = {36, 52, 100, 116, 132, 149, 165};
    static const std::vector<unsigned> starts160 = {36, 100, 149};
    static const std::vector<unsigned> none;
    return mhz == 40 ? starts40 : mhz == 80 ? starts80 : mhz == 160 ? starts160 : none;
}

bool channelFitsBand(unsigned ch, WifiBand band)
{
    return band == WifiBand::Band2G4 ? (ch >= 1 && ch <= 14) : (ch >= 7 && ch <= 196);
}
}  // namespace

std::optional<Chanspec> Chanspec::decode(uint16_t word)
{
    Chanspec cs;
    cs.raw = word;
    cs.centerChannel = uint8_t(word & 0xFF);
    cs.sideband = uint8_t((word >> 8) & 0x7);
    switch ((word >> 11) & 0x7)
    {
        case 2:
            cs.bandwidthMHz = 20;
            break;
        case 3:
            cs.bandwidthMHz = 40;
            break;
        case 4:
            cs.bandwidthMHz = 80;
            break;
        case 5:
            cs.bandwidthMHz = 160;
            break;
        default:
            return std::nullopt;  // 80+80 (code 6: two channel indices, not a channel number)
                                  // and the reserved codes
    }
    const uint16_t band = word & kBandMask;
    if (band == kBand5G)
        cs.band = WifiBand::Band5G;
    else if (band == kBand2G)
        cs.band = WifiBand::Band2G4;
    else
        return std::nullopt;
    if (!channelFitsBand(cs.centerChannel, cs.band)) return std::nullopt;
    if (cs.band == WifiBand::Band2G4 && cs.bandwidthMHz > 40) return std::nullopt;
    if (cs.sideband >= sidebandCount(cs.bandwidthMHz)) return std::nullopt;
    if (cs.bandwidthMHz == 160)
    {
        // Only three 160 MHz channels exist (centres 50, 114, 163).
        const auto& starts = blockStarts(160);
        if (std::none_of(
                starts.begin(), starts.end(),
                [&](unsigned start) { return cs.centerChannel == start + 14; }))
            return std::nullopt;
    }
    return cs;
}

Chanspec Chanspec::make(unsigned centerChannel, unsigned bandwidthMHz, unsigned sideband)
{
    const unsigned bwCode = bandwidthCode(bandwidthMHz);
    if (!bwCode)
        throw std::invalid_argument(
            "unsupported bandwidth " + std::to_string(bandwidthMHz) + " MHz (20, 40, 80 or 160)");
    const WifiBand band = centerChannel <= 14 ? WifiBand::Band2G4 : WifiBand::Band5G;
    const uint16_t word = uint16_t(
        (band == WifiBand::Band5G ? kBand5G : kBand2G) | (bwCode << 11) | ((sideband & 7) << 8) |
        (centerChannel & 0xFF));
    auto cs = decode(word);
    if (!cs || centerChannel > 0xFF)
        throw std::invalid_argument(
            "impossible channel " + std::to_string(centerChannel) + "/" +
            std::to_string(bandwidthMHz) + " sideband " + std::to_string(sideband));
    return *cs;
}

double Chanspec::centerFrequencyHz() const
{
    if (band == WifiBand::Band5G) return (5000.0 + 5.0 * centerChannel) * 1e6;
    if (centerChannel == 14) return 2484e6;
    return (2407.0 + 5.0 * centerChannel) * 1e6;
}

unsigned Chanspec::controlChannel() const
{
    // 20 MHz sub-channels are 4 channel numbers apart; the lowest is center − 2·(n−1).
    const unsigned n = sidebandCount(bandwidthMHz);
    return centerChannel - 2 * (n - 1) + 4 * sideband;
}

std::optional<Chanspec> Chanspec::fromControlChannel(unsigned control, unsigned mhz)
{
    if (mhz == 20)
    {
        if (control == 0 || control > 196) return std::nullopt;
        return make(control, 20);
    }
    const unsigned width = mhz / 20;
    for (unsigned start : blockStarts(mhz))
        if (control >= start && control < start + 4 * width && (control - start) % 4 == 0)
            return make(start + 2 * (width - 1), mhz, (control - start) / 4);
    return std::nullopt;
}

std::string Chanspec::asBroadcomString() const
{
    return std::to_string(controlChannel()) + "/" + std::to_string(bandwidthMHz);
}

std::string Chanspec::asString() const
{
    return std::to_string(centerChannel) + "/" + std::to_string(bandwidthMHz);
}

Chanspec Chanspec::fromString(const std::string& text)
{
    const auto slash = text.find('/');
    try
    {
        size_t used = 0;
        const unsigned long ch = std::stoul(text.substr(0, slash), &used);
        if (used != (slash == std::string::npos ? text.size() : slash))
            throw std::invalid_argument("");
        unsigned long bw = 20;
        if (slash != std::string::npos)
        {
            const std::string bwText = text.substr(slash + 1);
            bw = std::stoul(bwText, &used);
            if (used != bwText.size()) throw std::invalid_argument("");
        }
        if (bw != 20 && ch > 14)
            if (auto fromControl = fromControlChannel(unsigned(ch), unsigned(bw)))
                return *fromControl;
        return make(unsigned(ch), unsigned(bw));
    }
    catch (const std::invalid_argument& e)
    {
        throw std::invalid_argument(
            "invalid chanspec '" + text + "' (expected CHANNEL/BANDWIDTH, e.g. 155/80)" +
            (e.what()[0] ? std::string(": ") + e.what() : std::string()));
    }
    catch (const std::out_of_range&)
    {
        throw std::invalid_argument("invalid chanspec '" + text + "': number out of range");
    }
}

}  // namespace mrpt_wifi
