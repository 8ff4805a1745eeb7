/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace mrpt_wifi
{
enum class WifiBand : uint8_t
{
    Band2G4 = 0,
    Band5G = 1
};

/** A Broadcom d11ac chanspec word, decoded.
 *
 * Layout (DESIGN.md §4): bits 0–7 center channel, 8–10 control sideband,
 * 11–13 bandwidth (2=20, 3=40, 4=80, 5=160 MHz), 14–15 band (0 = 2.4 GHz, 3 = 5 GHz).
 * 80+80 MHz (code 6) packs two 80 MHz channel indices into bits 0–7 instead of a channel number:
 * not decoded (decode() returns nullopt). */
struct Chanspec
{
    uint16_t raw = 0;
    uint8_t centerChannel = 0;  //!< 802.11 center channel number
    uint16_t bandwidthMHz = 0;  //!< 20, 40, 80 or 160
    WifiBand band = WifiBand::Band5G;
    uint8_t sideband = 0;  //!< control sideband index (0 = lowest 20 MHz)

    /** Decodes a chanspec word; nullopt for a bandwidth, band or channel this chip can't use. */
    static std::optional<Chanspec> decode(uint16_t word);
    /** Builds (and encodes) a chanspec; throws std::invalid_argument for impossible combinations.
     */
    static Chanspec make(unsigned centerChannel, unsigned bandwidthMHz, unsigned sideband = 0);

    /** FFT size of one CSI report at this bandwidth: 64 / 128 / 256 / 512. */
    unsigned nfft() const { return 64u * (bandwidthMHz / 20u); }
    /** Center frequency: 5000 + 5·ch MHz (5 GHz), 2407 + 5·ch MHz (2.4 GHz; ch 14 = 2484). */
    double centerFrequencyHz() const;
    /** Control (primary 20 MHz) channel. */
    unsigned controlChannel() const;
    /** `155/80`: center channel / bandwidth, this project's convention (DESIGN.md §6). */
    std::string asString() const;
    /** `157/80`: control channel / bandwidth, the notation of Broadcom's `wl chanspec` and
     * `makecsiparams -c` (the same chanspec as center 155/80, sideband 2). */
    std::string asBroadcomString() const;
    /** Parses `CH/BW` (or `CH` for 20 MHz). At 40/80/160 MHz in the 5 GHz band CH may be the
     * center channel (155/80, 50/160) or a control channel (157/80, 36/160): the two sets don't
     * overlap.
     * Throws std::invalid_argument naming the text. */
    static Chanspec fromString(const std::string& text);
    /** The 40/80/160 MHz chanspec whose 20 MHz sub-channel `controlChannel` is (5 GHz plan);
     *  nullopt if that channel starts no such block. 20 MHz: the channel itself. */
    static std::optional<Chanspec> fromControlChannel(
        unsigned controlChannel, unsigned bandwidthMHz);

    /** Same radio channel: center, bandwidth and band (the control sideband may differ: the
     * receiver's and a transmitter's chanspec of one channel can name different primaries). */
    bool sameChannel(const Chanspec& o) const
    {
        return centerChannel == o.centerChannel && bandwidthMHz == o.bandwidthMHz && band == o.band;
    }
    bool operator==(const Chanspec& o) const { return raw == o.raw; }
    bool operator!=(const Chanspec& o) const { return raw != o.raw; }
};

}  // namespace mrpt_wifi
