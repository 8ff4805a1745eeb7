/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/MacAddress.h>

#include <cstdio>
#include <stdexcept>

namespace mrpt_wifi
{
namespace
{
int hexValue(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/** Splits `xx:xx:...` into six tokens; each token is two hex digits or (if allowed) `*`. */
template <typename OnByte>
bool parseSixTokens(std::string_view text, bool allowWildcard, OnByte onByte)
{
    size_t pos = 0;
    for (int i = 0; i < 6; ++i)
    {
        if (i > 0)
        {
            if (pos >= text.size() || (text[pos] != ':' && text[pos] != '-')) return false;
            ++pos;
        }
        if (allowWildcard && pos < text.size() && text[pos] == '*')
        {
            onByte(i, -1);
            ++pos;
            continue;
        }
        if (pos + 2 > text.size()) return false;
        const int hi = hexValue(text[pos]), lo = hexValue(text[pos + 1]);
        if (hi < 0 || lo < 0) return false;
        onByte(i, hi * 16 + lo);
        pos += 2;
    }
    return pos == text.size();
}
}  // namespace

std::optional<MacAddress> MacAddress::parse(std::string_view text)
{
    MacAddress m;
    if (!parseSixTokens(text, false, [&](int i, int v) { m.bytes[i] = uint8_t(v); }))
        return std::nullopt;
    return m;
}

MacAddress MacAddress::fromString(std::string_view text)
{
    auto m = parse(text);
    if (!m)
        throw std::invalid_argument(
            "invalid MAC address '" + std::string(text) + "' (expected aa:bb:cc:dd:ee:ff)");
    return *m;
}

std::string MacAddress::asString() const
{
    char buf[18];
    std::snprintf(
        buf, sizeof(buf), "%02x:%02x:%02x:%02x:%02x:%02x", bytes[0], bytes[1], bytes[2], bytes[3],
        bytes[4], bytes[5]);
    return buf;
}

uint64_t MacAddress::asUint64() const
{
    uint64_t v = 0;
    for (uint8_t b : bytes) v = (v << 8) | b;
    return v;
}

MacPattern MacPattern::fromString(std::string_view pattern)
{
    MacPattern p;
    const bool ok = parseSixTokens(
        pattern, true,
        [&](int i, int v)
        {
            p.wildcard_[i] = v < 0;
            p.value_.bytes[i] = v < 0 ? 0 : uint8_t(v);
        });
    if (!ok)
        throw std::invalid_argument(
            "invalid MAC pattern '" + std::string(pattern) +
            "' (expected aa:bb:cc:dd:ee:ff, any byte may be '*')");
    return p;
}

bool MacPattern::matches(const MacAddress& mac) const
{
    for (int i = 0; i < 6; ++i)
        if (!wildcard_[i] && mac.bytes[i] != value_.bytes[i]) return false;
    return true;
}

std::string MacPattern::asString() const
{
    const std::string full = value_.asString();
    std::string out;
    for (int i = 0; i < 6; ++i)
    {
        if (i) out += ':';
        out += wildcard_[i] ? std::string("*") : full.substr(size_t(i) * 3, 2);
    }
    return out;
}

}  // namespace mrpt_wifi
