/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/emulator/ToolResult.h>
#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/obs/MacAddress.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mrpt_wifi::emulator
{
constexpr size_t kCsiParamsBytes = 34;  //!< size of the nexmon_csi parameter struct (ioctl 500)
constexpr size_t kMaxMacFilters = 4;
/** Delay makecsiparams puts in when ≥ 12 (core, stream) pairs are asked for and -d isn't given. */
constexpr uint16_t kDefaultBusyDelay_us = 50;

/** The CSI extraction settings nexutil -s500 hands to the firmware, i.e. the 34-byte struct
 * makecsiparams prints in base64. Little-endian:
 *
 * | bytes | field |
 * |---|---|
 * | 0–1 | uint16 chanspec |
 * | 2 | uint8 csi_collect (1 on, 0 off) |
 * | 3 | uint8 core_nss_mask = nss_mask << 4 \| core_mask |
 * | 4 | uint8 use_pkt_filter |
 * | 5 | uint8 first_pkt_byte (802.11 frame-control byte to match) |
 * | 6–7 | uint16 n_mac_addr (0: no MAC filter) |
 * | 8–31 | 4 × 6 bytes source MACs, in address byte order |
 * | 32–33 | uint16 delay [µs] the CSI engine stays busy after each report |
 */
struct CsiParams
{
    uint16_t chanspecWord = 0;  //!< 0 when makecsiparams got no -c (allowed with -e 0)
    bool collect = false;
    uint8_t coreMask = 0;  //!< bit i: receive core i
    uint8_t nssMask = 0;   //!< bit i: spatial stream i
    bool usePacketFilter = false;
    uint8_t firstPacketByte = 0;
    std::vector<MacAddress> macFilter;  //!< at most kMaxMacFilters
    uint16_t delay_us = 0;

    std::array<uint8_t, kCsiParamsBytes> toBytes() const;
    /** Parses the struct; throws std::invalid_argument if the length is not 34 or n_mac_addr
     * exceeds 4 (what the firmware rejects). */
    static CsiParams fromBytes(const uint8_t* data, size_t len);

    std::optional<Chanspec> chanspec() const { return Chanspec::decode(chanspecWord); }

    /** The BCM4366c0 hardware MAC filter: compares only the first two bytes of the source MAC
     * with each entry (DESIGN.md §4), so 11:22:33:44:55:66 also lets 11:22:99:… through.
     * True when there is no filter. */
    bool hardwareMacFilterPasses(const MacAddress& source) const;

    bool operator==(const CsiParams& o) const;
};

/** Standard base64 (RFC 4648, with '=' padding). */
std::string base64Encode(const uint8_t* data, size_t len);
/** Strict base64 decoding (padding required, no whitespace inside); nullopt if malformed. */
std::optional<std::vector<uint8_t>> base64Decode(std::string_view text);

/** Parses a chanspec as the router tools take it: "CH/BW" (CH a centre channel, the project's
 * convention, see Chanspec::fromString), "CH" (20 MHz) or a raw word "0xe09b". Throws
 * std::invalid_argument naming the text. */
Chanspec parseRouterChanspec(const std::string& text);

/** `makecsiparams [-h] [-r] [-e 0|1] [-c CH/BW] [-C COREMASK] [-N NSSMASK] [-m MAC[,MAC...]]
 * [-b BYTE] [-d DELAY_US]`: prints the base64 (or with -r the raw bytes) of the struct, like the
 * Nexmon tool. Unlike the real one (which always exits 0), errors exit 1. `args` excludes the
 * program name. A pure function: the shim runs it locally, the emulator through its socket. */
ToolResult makeCsiParams(const Argv& args);

/** The struct makeCsiParams() would print for `args`; throws std::invalid_argument with the
 * tool's message on bad arguments. */
CsiParams csiParamsFromArguments(const Argv& args);

}  // namespace mrpt_wifi::emulator
