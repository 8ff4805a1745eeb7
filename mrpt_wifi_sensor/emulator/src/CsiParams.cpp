/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/emulator/CsiParams.h>

#include <algorithm>
#include <bitset>
#include <cctype>
#include <cstring>
#include <stdexcept>

namespace mrpt_wifi::emulator
{
namespace
{
constexpr char kBase64Alphabet[] =
    "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

int base64Value(char c)
{
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
}

void putLE16(uint8_t* p, uint16_t v)
{
    p[0] = uint8_t(v);
    p[1] = uint8_t(v >> 8);
}
uint16_t getLE16(const uint8_t* p)
{
    return uint16_t(p[0] | (p[1] << 8));
}

/** Offsets in the struct. */
constexpr size_t kOffChanspec = 0, kOffCollect = 2, kOffCoreNss = 3, kOffUseFilter = 4,
                 kOffFirstByte = 5, kOffMacCount = 6, kOffMacs = 8, kOffDelay = 32;
}  // namespace

std::array<uint8_t, kCsiParamsBytes> CsiParams::toBytes() const
{
    if (macFilter.size() > kMaxMacFilters)
        throw std::invalid_argument("at most 4 MAC addresses fit in the CSI parameters");
    std::array<uint8_t, kCsiParamsBytes> b{};
    putLE16(&b[kOffChanspec], chanspecWord);
    b[kOffCollect] = collect ? 1 : 0;
    b[kOffCoreNss] = uint8_t((nssMask & 0x0F) << 4 | (coreMask & 0x0F));
    b[kOffUseFilter] = usePacketFilter ? 1 : 0;
    b[kOffFirstByte] = firstPacketByte;
    putLE16(&b[kOffMacCount], uint16_t(macFilter.size()));
    for (size_t i = 0; i < macFilter.size(); ++i)
        std::memcpy(&b[kOffMacs + 6 * i], macFilter[i].bytes.data(), 6);
    putLE16(&b[kOffDelay], delay_us);
    return b;
}

CsiParams CsiParams::fromBytes(const uint8_t* data, size_t len)
{
    if (len != kCsiParamsBytes)
        throw std::invalid_argument(
            "CSI parameters are " + std::to_string(kCsiParamsBytes) + " bytes, got " +
            std::to_string(len));
    CsiParams p;
    p.chanspecWord = getLE16(data + kOffChanspec);
    p.collect = data[kOffCollect] != 0;
    p.coreMask = data[kOffCoreNss] & 0x0F;
    p.nssMask = uint8_t(data[kOffCoreNss] >> 4);
    p.usePacketFilter = data[kOffUseFilter] != 0;
    p.firstPacketByte = data[kOffFirstByte];
    const uint16_t nMacs = getLE16(data + kOffMacCount);
    if (nMacs > kMaxMacFilters)
        throw std::invalid_argument(
            "n_mac_addr = " + std::to_string(nMacs) + " (at most " +
            std::to_string(kMaxMacFilters) + ")");
    for (size_t i = 0; i < nMacs; ++i)
    {
        MacAddress m;
        std::memcpy(m.bytes.data(), data + kOffMacs + 6 * i, 6);
        p.macFilter.push_back(m);
    }
    p.delay_us = getLE16(data + kOffDelay);
    return p;
}

bool CsiParams::hardwareMacFilterPasses(const MacAddress& source) const
{
    if (macFilter.empty()) return true;
    return std::any_of(
        macFilter.begin(), macFilter.end(),
        [&](const MacAddress& m)
        { return m.bytes[0] == source.bytes[0] && m.bytes[1] == source.bytes[1]; });
}

bool CsiParams::operator==(const CsiParams& o) const
{
    return toBytes() == o.toBytes();
}

std::string base64Encode(const uint8_t* data, size_t len)
{
    std::string out;
    out.reserve((len + 2) / 3 * 4);
    for (size_t i = 0; i < len; i += 3)
    {
        const size_t n = std::min<size_t>(3, len - i);
        uint32_t group = uint32_t(data[i]) << 16;
        if (n > 1) group |= uint32_t(data[i + 1]) << 8;
        if (n > 2) group |= data[i + 2];
        out += kBase64Alphabet[(group >> 18) & 63];
        out += kBase64Alphabet[(group >> 12) & 63];
        out += n > 1 ? kBase64Alphabet[(group >> 6) & 63] : '=';
        out += n > 2 ? kBase64Alphabet[group & 63] : '=';
    }
    return out;
}

std::optional<std::vector<uint8_t>> base64Decode(std::string_view text)
{
    if (text.size() % 4 != 0) return std::nullopt;
    std::vector<uint8_t> out;
    out.reserve(text.size() / 4 * 3);
    for (size_t i = 0; i < text.size(); i += 4)
    {
        const bool last = i + 4 == text.size();
        int v[4];
        int padding = 0;
        for (int k = 0; k < 4; ++k)
        {
            const char c = text[i + size_t(k)];
            if (c == '=' && last && k >= 2)
            {
                ++padding;
                v[k] = 0;
                continue;
            }
            if (padding) return std::nullopt;  // data after '='
            v[k] = base64Value(c);
            if (v[k] < 0) return std::nullopt;
        }
        const uint32_t group =
            uint32_t(v[0]) << 18 | uint32_t(v[1]) << 12 | uint32_t(v[2]) << 6 | uint32_t(v[3]);
        out.push_back(uint8_t(group >> 16));
        if (padding < 2) out.push_back(uint8_t(group >> 8));
        if (padding < 1) out.push_back(uint8_t(group));
    }
    return out;
}

Chanspec parseRouterChanspec(const std::string& text)
{
    if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X'))
    {
        unsigned long word = 0;
        const auto cs =
            parseUnsigned(text, 0xFFFF, word) ? Chanspec::decode(uint16_t(word)) : std::nullopt;
        if (!cs) throw std::invalid_argument("invalid chanspec word '" + text + "'");
        return *cs;
    }
    return Chanspec::fromString(text);
}

namespace
{
/** ether_aton-like: six ':'-separated groups of 1–2 hex digits. */
std::optional<MacAddress> parseEtherAddress(const std::string& text)
{
    MacAddress m;
    size_t pos = 0;
    for (int i = 0; i < 6; ++i)
    {
        size_t digits = 0;
        unsigned value = 0;
        while (pos < text.size() && digits < 2 && std::isxdigit(uint8_t(text[pos])))
        {
            const char c = char(std::tolower(uint8_t(text[pos++])));
            value = value * 16 + unsigned(c <= '9' ? c - '0' : c - 'a' + 10);
            ++digits;
        }
        if (!digits) return std::nullopt;
        m.bytes[size_t(i)] = uint8_t(value);
        if (i < 5)
        {
            if (pos >= text.size() || text[pos] != ':') return std::nullopt;
            ++pos;
        }
    }
    if (pos != text.size()) return std::nullopt;
    return m;
}
}  // namespace

CsiParams csiParamsFromArguments(const Argv& args)
{
    CsiParams p;
    p.collect = true;  // -e defaults to 1
    bool delayGiven = false;
    ShortOptionParser opts(args, "hre:m:b:c:C:N:d:");
    char o;
    std::string v;
    unsigned long n = 0;
    while (opts.next(o, v))
    {
        switch (o)
        {
            case 'h':
            case 'r':
                break;  // handled by makeCsiParams()
            case 'e':
                if (!parseUnsigned(v, 0xFF, n)) throw std::invalid_argument("Invalid enable value");
                p.collect = n != 0;
                break;
            case 'm':
            {
                size_t start = 0;
                while (start <= v.size())
                {
                    const size_t comma = std::min(v.find(',', start), v.size());
                    const std::string one = v.substr(start, comma - start);
                    start = comma + 1;
                    if (one.empty()) continue;  // strtok skips empty tokens
                    if (p.macFilter.size() >= kMaxMacFilters)
                        throw std::invalid_argument("Only 4 mac addresses can be given");
                    const auto mac = parseEtherAddress(one);
                    if (!mac) throw std::invalid_argument("Invalid mac address");
                    p.macFilter.push_back(*mac);
                }
                break;
            }
            case 'b':
                if (!parseUnsigned(v, 0xFF, n)) throw std::invalid_argument("Invalid byte filter");
                p.usePacketFilter = true;
                p.firstPacketByte = uint8_t(n);
                break;
            case 'c':
                try
                {
                    p.chanspecWord = parseRouterChanspec(v).raw;
                }
                catch (const std::invalid_argument&)
                {
                    throw std::invalid_argument("Invalid chanspec");
                }
                break;
            case 'C':
                if (!parseUnsigned(v, 0x0F, n)) throw std::invalid_argument("Invalid core mask");
                p.coreMask = uint8_t(n);
                break;
            case 'N':
                if (!parseUnsigned(v, 0x0F, n)) throw std::invalid_argument("Invalid nss mask");
                p.nssMask = uint8_t(n);
                break;
            case 'd':
                if (!parseUnsigned(v, 0xFFFF, n)) throw std::invalid_argument("Invalid delay");
                p.delay_us = uint16_t(n);
                delayGiven = true;
                break;
            default:
                throw std::invalid_argument("Invalid option");
        }
    }
    if (!opts.error().empty()) throw std::invalid_argument("Invalid option");
    if (!opts.remaining().empty())
        throw std::invalid_argument("Unexpected argument '" + opts.remaining().front() + "'");
    if (p.collect)
    {
        if (!p.chanspecWord) throw std::invalid_argument("No channel given");
        if (!p.coreMask || !p.nssMask)
            throw std::invalid_argument("No nssmask and/or coremask given");
    }
    // Like the real tool: 3x4, 4x3 and 4x4 need a pause after each report.
    const size_t pairs = std::bitset<4>(p.coreMask).count() * std::bitset<4>(p.nssMask).count();
    if (!delayGiven && pairs >= 12) p.delay_us = kDefaultBusyDelay_us;
    return p;
}

ToolResult makeCsiParams(const Argv& args)
{
    static const char* kUsage =
        "Usage: makecsiparams [OPTION...]\n"
        "\n"
        "   -h           print this message\n"
        "   -e on/off    enable/disable CSI collection (0 = disable, default is 1)\n"
        "   -c chanspec  channel specification <channel>/<bandwidth> (or 0xNNNN)\n"
        "   -C coremask  bitmask with cores where to activate capture\n"
        "                (e.g., 0x5 = 0b0101 set core 0 and 2)\n"
        "   -N nssmask   bitmask with spatial streams to capture\n"
        "                (e.g., 0x7 = 0b0111 capture first 3 ss)\n"
        "   -m addr      filter on this source mac address (up to four, comma separated)\n"
        "   -b byte      filter frames starting with byte\n"
        "   -d delay     delay in us after each CSI operation\n"
        "                (really needed for 3x4, 4x3 and 4x4 configurations,\n"
        "                without it is enforced automatically)\n"
        "   -r           generate raw output (no base64)\n";
    if (args.empty()) return ToolResult::success(kUsage);
    bool raw = false;
    {
        ShortOptionParser scan(args, "hre:m:b:c:C:N:d:");
        char o;
        std::string v;
        while (scan.next(o, v))
        {
            if (o == 'h') return ToolResult::success(kUsage);
            if (o == 'r') raw = true;
        }
    }
    try
    {
        const auto bytes = csiParamsFromArguments(args).toBytes();
        if (raw) return ToolResult::success(std::string(bytes.begin(), bytes.end()));
        return ToolResult::success(base64Encode(bytes.data(), bytes.size()) + "\n");
    }
    catch (const std::invalid_argument& e)
    {
        return ToolResult::failure(e.what());
    }
}

}  // namespace mrpt_wifi::emulator
