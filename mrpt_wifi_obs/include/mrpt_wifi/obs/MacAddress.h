/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace mrpt_wifi
{
/** A 48-bit IEEE 802 MAC address, printed as lowercase `aa:bb:cc:dd:ee:ff`. */
struct MacAddress
{
    std::array<uint8_t, 6> bytes{};

    /** Parses `aa:bb:cc:dd:ee:ff` (or `-` separators, any case); nullopt if malformed. */
    static std::optional<MacAddress> parse(std::string_view text);
    /** As parse(), but throws std::invalid_argument naming the text. */
    static MacAddress fromString(std::string_view text);

    std::string asString() const;
    /** The 48 bits as an integer (first byte most significant): handy as a map key or ID. */
    uint64_t asUint64() const;

    bool operator==(const MacAddress& o) const { return bytes == o.bytes; }
    bool operator!=(const MacAddress& o) const { return bytes != o.bytes; }
    bool operator<(const MacAddress& o) const { return bytes < o.bytes; }
};

/** A MAC pattern with per-byte wildcards, e.g. `11:11:11:*:*:*`. */
class MacPattern
{
public:
    /** Parses the pattern; throws std::invalid_argument naming it if malformed. */
    static MacPattern fromString(std::string_view pattern);
    bool matches(const MacAddress& mac) const;
    std::string asString() const;

private:
    MacAddress value_;
    std::array<bool, 6> wildcard_{};
};

}  // namespace mrpt_wifi

template <>
struct std::hash<mrpt_wifi::MacAddress>
{
    size_t operator()(const mrpt_wifi::MacAddress& m) const noexcept
    {
        return std::hash<uint64_t>{}(m.asUint64());
    }
};
