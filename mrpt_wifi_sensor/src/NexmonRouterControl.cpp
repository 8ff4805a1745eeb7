/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/system/string_utils.h>
#include <mrpt_wifi/sensor/NexmonRouterControl.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <regex>
#include <sstream>

namespace mrpt_wifi
{
namespace
{
std::string hexByte(unsigned v)
{
    char buf[8];
    std::snprintf(buf, sizeof(buf), "0x%x", v);
    return buf;
}

/** Base64 on one line (MRPT's encoder wraps lines; nexutil -v wants one word). */
std::string base64OneLine(const std::vector<uint8_t>& bytes)
{
    std::string s;
    mrpt::system::encodeBase64(bytes, s);
    s.erase(
        std::remove_if(s.begin(), s.end(), [](char c) { return c == '\n' || c == '\r'; }), s.end());
    return s;
}

std::optional<Chanspec> chanspecFromFrequencyMHz(int freqMHz)
{
    try
    {
        if (freqMHz >= 5000) return Chanspec::make(unsigned(freqMHz - 5000) / 5, 20);
        if (freqMHz == 2484) return Chanspec::make(14, 20);
        if (freqMHz >= 2412) return Chanspec::make(unsigned(freqMHz - 2407) / 5, 20);
    }
    catch (const std::invalid_argument&)
    {
    }
    return std::nullopt;
}
bool onlyCharsOf(const std::string& s, const char* extra)
{
    return !s.empty() && std::all_of(
                             s.begin(), s.end(),
                             [extra](char c)
                             {
                                 return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                                        (c >= '0' && c <= '9') ||
                                        (c != '\0' && std::strchr(extra, c));
                             });
}
constexpr const char* kNameExtra = "_.-";
constexpr const char* kPathExtra = "_./+@%:,=-";
}  // namespace

std::string shellQuote(const std::string& word)
{
    if (onlyCharsOf(word, kPathExtra)) return word;
    std::string q = "'";
    for (char c : word) q += (c == '\'' ? std::string("'\\''") : std::string(1, c));
    return q + "'";
}

void RouterSetupOptions::validate() const
{
    const auto check =
        [](const std::string& key, const std::string& value, const char* extra, const char* what)
    {
        if (!onlyCharsOf(value, extra))
            throw std::invalid_argument(
                "key '" + key + "': '" + value + "' is not " + what +
                " (it is sent to the router's shell)");
    };
    check(
        "setup_module_path", modulePath, kPathExtra,
        "a module path ([A-Za-z0-9_./+@%:,=-], no whitespace or shell metacharacters)");
    check("setup_bridge", bridge, kNameExtra, "a bridge name ([A-Za-z0-9_.-]+)");
    check("setup_interface_5g", interface5G, kNameExtra, "an interface name ([A-Za-z0-9_.-]+)");
    check("setup_interface_2g4", interface2G4, kNameExtra, "an interface name ([A-Za-z0-9_.-]+)");
}

NexmonRouterControl::NexmonRouterControl(
    std::shared_ptr<RouterShell> shell, RouterSetupOptions options)
    : shell_(std::move(shell)), options_(std::move(options))
{
    options_.validate();
}

std::string NexmonRouterControl::interfaceFor(WifiBand band) const
{
    return band == WifiBand::Band5G ? options_.interface5G : options_.interface2G4;
}

void NexmonRouterControl::loadFirmwareModule(bool bridge2G4)
{
    // rmmod may fail when the module isn't loaded yet: that's fine, insmod decides.
    std::string command = "rmmod dhd; insmod " + shellQuote(options_.modulePath) +
                          " && brctl addif " + shellQuote(options_.bridge) + " " +
                          shellQuote(options_.interface5G);
    if (bridge2G4)
        command += " && brctl addif " + shellQuote(options_.bridge) + " " +
                   shellQuote(options_.interface2G4);
    shell_->run(command, options_.commandTimeout_s);
}

std::string NexmonRouterControl::configureCommand(const CsiExtractionSettings& s) const
{
    if (s.macFilter.size() > 4)
        throw std::invalid_argument("the firmware filters at most 4 MAC addresses");
    const std::string iface = shellQuote(interfaceFor(s.chanspec.band));
    const std::string cs = s.chanspec.asBroadcomString();
    std::string params = "makecsiparams -e 1 -c " + cs + " -C " + hexByte(s.coreMask) + " -N " +
                         hexByte(s.streamMask);
    if (!s.macFilter.empty())
    {
        params += " -m ";
        for (size_t i = 0; i < s.macFilter.size(); ++i)
            params += (i ? "," : "") + s.macFilter[i].asString();
    }
    if (s.delay) params += " -d " + std::to_string(s.delay);
    if (s.firstPacketByte) params += " -b " + hexByte(*s.firstPacketByte);
    // One round trip; && stops at the first failure so its error is the one reported.
    return "wl -i " + iface + " chanspec " + cs + " && wl -i " + iface +
           " monitor 1 && nexutil -I " + iface + " -s500 -b -l34 -v $(" + params + ")";
}

std::string NexmonRouterControl::stopCaptureCommand(const Chanspec& cs) const
{
    const std::string iface = shellQuote(interfaceFor(cs.band));
    return "nexutil -I " + iface + " -s500 -b -l34 -v $(makecsiparams -e 0 -c " +
           cs.asBroadcomString() + ")";
}

void NexmonRouterControl::stopCapture(const Chanspec& cs)
{
    shell_->run(stopCaptureCommand(cs), options_.commandTimeout_s);
}

void NexmonRouterControl::configure(const CsiExtractionSettings& s)
{
    shell_->run(configureCommand(s), options_.commandTimeout_s);
}

Chanspec NexmonRouterControl::currentChanspec(WifiBand band)
{
    const std::string out = shell_->run(
        "wl -i " + shellQuote(interfaceFor(band)) + " chanspec", options_.commandTimeout_s);
    // "157/80 (0xe29b)": the hex word is unambiguous.
    static const std::regex hexWord("0x([0-9a-fA-F]{4})");
    std::smatch m;
    if (std::regex_search(out, m, hexWord))
        if (auto cs = Chanspec::decode(uint16_t(std::stoul(m[1], nullptr, 16)))) return *cs;
    std::istringstream in(out);
    std::string word;
    in >> word;
    try
    {
        return Chanspec::fromString(word);
    }
    catch (const std::invalid_argument&)
    {
        throw RouterError(
            RouterErrorKind::WrongFirmware, "unexpected 'wl chanspec' answer: " + out);
    }
}

std::vector<ScannedAccessPoint> NexmonRouterControl::scan(WifiBand band)
{
    const std::string iface = shellQuote(interfaceFor(band));
    char wait[32];
    std::snprintf(wait, sizeof(wait), "%.1f", options_.scanWait_s);
    const std::string out = shell_->run(
        "wl -i " + iface + " scan && sleep " + wait + " && wl -i " + iface + " scanresults",
        options_.commandTimeout_s + options_.scanWait_s);
    return parseWlScanResults(out);
}

void NexmonRouterControl::startTransmitter(const TransmitterSettings& t, WifiBand band)
{
    const std::string iface = shellQuote(interfaceFor(band));
    const auto frame = makeBeaconFrame(t.source, "mrpt_wifi", 0);
    const unsigned periodUs = unsigned(1e6 / std::max(0.1, t.rate_Hz));
    std::ostringstream cmd;
    // A bounded loop on the router, in the background: it ends by itself after `count` frames.
    cmd << "wl -i " << iface << " 5g_rate -v 0 -s " << t.streams << " && (n=0; while [ $n -lt "
        << t.count << " ]; do nexutil -I " << iface << " -s505 -b -l " << frame.size() << " -v "
        << base64OneLine(frame) << " || exit 1; usleep " << periodUs
        << "; n=$((n+1)); done) >/dev/null 2>&1 &";
    shell_->run(cmd.str(), options_.commandTimeout_s);
}

void NexmonRouterControl::stopTransmitter()
{
    shell_->run("pkill -f 'nexutil.*-s505' ; true", options_.commandTimeout_s);
}

std::vector<ScannedAccessPoint> parseWlScanResults(const std::string& text)
{
    static const std::regex ssidRe(R"(^SSID: \"(.*)\")");
    static const std::regex rssiRe(R"(RSSI: (-?\d+) dBm)");
    static const std::regex noiseRe(R"(noise: (-?\d+) dBm)");
    static const std::regex channelRe(R"(Channel: (\d+(?:/\d+)?))");
    static const std::regex bssidRe(R"(^BSSID: ([0-9A-Fa-f:]{17}))");
    static const std::regex chanspecRe(R"(Chanspec:.*\(0x([0-9a-fA-F]{4})\))");

    std::vector<ScannedAccessPoint> aps;
    std::optional<ScannedAccessPoint> cur;
    bool haveChannel = false, haveBssid = false;
    const auto finish = [&]
    {
        if (cur && haveChannel && haveBssid) aps.push_back(*cur);
        cur.reset();
        haveChannel = haveBssid = false;
    };
    std::istringstream in(text);
    std::smatch m;
    for (std::string line; std::getline(in, line);)
    {
        if (std::regex_search(line, m, ssidRe))
        {
            finish();
            cur = ScannedAccessPoint{};
            cur->ssid = m[1];
            continue;
        }
        if (!cur) continue;
        if (std::regex_search(line, m, rssiRe)) cur->rssi_dBm = std::stoi(m[1]);
        if (std::regex_search(line, m, noiseRe)) cur->noise_dBm = std::stoi(m[1]);
        if (std::regex_search(line, m, channelRe))
        {
            try
            {
                cur->chanspec = Chanspec::fromString(m[1]);
                haveChannel = true;
            }
            catch (const std::invalid_argument&)
            {
            }
        }
        if (std::regex_search(line, m, chanspecRe))
            if (auto cs = Chanspec::decode(uint16_t(std::stoul(m[1], nullptr, 16))))
                cur->chanspec = *cs, haveChannel = true;
        if (std::regex_search(line, m, bssidRe))
            if (auto mac = MacAddress::parse(std::string(m[1])))
                cur->bssid = *mac, haveBssid = true;
    }
    finish();
    return aps;
}

std::vector<ScannedAccessPoint> scanWithHostInterface(const std::string& iface, double timeout_s)
{
    const auto r = runSubprocess({"iw", "dev", iface, "scan"}, timeout_s);
    if (r.timedOut || r.exitCode != 0)
        throw RouterError(
            r.timedOut ? RouterErrorKind::Timeout
                       : (r.exitCode == 127 ? RouterErrorKind::CommandMissing
                                            : RouterErrorKind::CommandFailed),
            "host scan 'iw dev " + iface + " scan' (exit " + std::to_string(r.exitCode) + "): " +
                (r.timedOut ? std::string("timed out") : r.err.substr(0, r.err.find('\n'))));
    return parseIwScan(r.out);
}

std::vector<ScannedAccessPoint> parseIwScan(const std::string& text)
{
    static const std::regex bssRe(R"(^BSS ([0-9a-fA-F:]{17}))");
    static const std::regex freqRe(R"(^\s*freq: (\d+))");
    static const std::regex signalRe(R"(^\s*signal: (-?[\d.]+) dBm)");
    static const std::regex ssidRe(R"(^\s*SSID: (.*)$)");
    static const std::regex widthRe(R"(\* channel width: (\d))");
    static const std::regex centerRe(R"(\* center freq segment 1: (\d+))");
    static const std::regex secondaryRe(R"(\* secondary channel offset: (above|below))");

    std::vector<ScannedAccessPoint> aps;
    std::optional<ScannedAccessPoint> cur;
    int primary = 0, vhtWidth = 0, vhtCenter = 0;
    std::string secondary;
    const auto finish = [&]
    {
        if (cur && primary)
        {
            std::optional<Chanspec> cs = Chanspec::fromControlChannel(unsigned(primary), 20);
            if (vhtWidth == 1 && vhtCenter)
                cs = Chanspec::fromControlChannel(unsigned(primary), 80);
            else if (!secondary.empty() && primary > 14)
                cs = Chanspec::fromControlChannel(unsigned(primary), 40);
            if (cs)
            {
                cur->chanspec = *cs;
                aps.push_back(*cur);
            }
        }
        cur.reset();
        primary = vhtWidth = vhtCenter = 0;
        secondary.clear();
    };
    std::istringstream in(text);
    std::smatch m;
    for (std::string line; std::getline(in, line);)
    {
        if (std::regex_search(line, m, bssRe))
        {
            finish();
            cur = ScannedAccessPoint{};
            cur->bssid = MacAddress::fromString(std::string(m[1]));
            continue;
        }
        if (!cur) continue;
        if (std::regex_search(line, m, freqRe))
            if (auto cs = chanspecFromFrequencyMHz(std::stoi(m[1]))) primary = cs->centerChannel;
        if (std::regex_search(line, m, signalRe)) cur->rssi_dBm = int(std::lround(std::stod(m[1])));
        if (std::regex_search(line, m, ssidRe)) cur->ssid = m[1];
        if (std::regex_search(line, m, widthRe)) vhtWidth = std::stoi(m[1]);
        if (std::regex_search(line, m, centerRe)) vhtCenter = std::stoi(m[1]);
        if (std::regex_search(line, m, secondaryRe)) secondary = m[1];
    }
    finish();
    return aps;
}

std::vector<uint8_t> makeBeaconFrame(
    const MacAddress& source, const std::string& ssid, unsigned channel)
{
    std::vector<uint8_t> f = {0x80, 0x00, 0x00, 0x00};            // beacon, duration 0
    f.insert(f.end(), 6, 0xFF);                                   // addr1: broadcast
    f.insert(f.end(), source.bytes.begin(), source.bytes.end());  // addr2: all six bytes right
    f.insert(f.end(), source.bytes.begin(), source.bytes.end());  // addr3: BSSID
    f.insert(f.end(), {0x00, 0x00});              // sequence control (firmware fills)
    f.insert(f.end(), 8, 0x00);                   // timestamp
    f.insert(f.end(), {0x64, 0x00, 0x01, 0x00});  // 100 TU, ESS
    const size_t ssidLen = std::min<size_t>(ssid.size(), 32);
    f.push_back(0x00);
    f.push_back(uint8_t(ssidLen));
    f.insert(f.end(), ssid.begin(), ssid.begin() + long(ssidLen));
    f.insert(f.end(), {0x01, 0x01, 0x8c});  // supported rates: 6 Mb/s (basic)
    if (channel) f.insert(f.end(), {0x03, 0x01, uint8_t(channel)});  // DS parameter set
    return f;
}

}  // namespace mrpt_wifi
