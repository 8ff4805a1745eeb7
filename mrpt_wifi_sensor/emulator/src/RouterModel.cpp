/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/emulator/RouterModel.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <set>
#include <stdexcept>

#include "Json.h"

namespace mrpt_wifi::emulator
{
using detail::JsonObject;
using detail::jsonQuote;

namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr const char* kDefaultWlInterface = "eth5";  // wl's first wireless adapter
constexpr const char* kDefaultNexutilInterface = "eth6";
constexpr const char* kBridge = "br0";
constexpr size_t kMinInjectedFrame = 24;  // an 802.11 MAC header
constexpr size_t kMaxInjectedFrame = 2304;

std::string baseName(const std::string& path)
{
    const auto slash = path.find_last_of('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string hex16(uint16_t v)
{
    char buf[8];
    std::snprintf(buf, sizeof(buf), "0x%04x", v);
    return buf;
}

std::string upperMac(const MacAddress& m)
{
    std::string s = m.asString();
    for (auto& c : s) c = char(std::toupper(uint8_t(c)));
    return s;
}

/** One BSS in the layout of `wl scanresults`. */
std::string formatScanEntry(const ScanEntry& e, const Chanspec& tunedTo)
{
    const Chanspec& cs = e.chanspec;
    std::string s = "SSID: \"" + e.ssid + "\"\n";
    s += "Mode: Managed\tRSSI: " + std::to_string(e.rssi_dBm) +
         " dBm\tSNR: " + std::to_string(e.rssi_dBm - e.noise_dBm) +
         " dB\tnoise: " + std::to_string(e.noise_dBm) + " dBm\tFlags: RSSI" +
         (cs.centerChannel == tunedTo.centerChannel ? " on-channel" : "") +
         " \tChannel: " + cs.asBroadcomString() + "\n";
    s += "BSSID: " + upperMac(e.bssid) + "\tCapability: ESS ShortSlot \n";
    s += cs.band == WifiBand::Band5G ? "Supported Rates: [ 6(b) 9 12(b) 18 24(b) 36 48 54 ]\n"
                                     : "Supported Rates: [ 1(b) 2(b) 5.5(b) 6 9 11(b) 12 18 "
                                       "24 36 48 54 ]\n";
    s += cs.bandwidthMHz >= 80 ? "VHT Capable:\n" : "HT Capable:\n";
    s += std::string("\tChanspec: ") + (cs.band == WifiBand::Band5G ? "5GHz" : "2.4GHz") +
         " channel " + std::to_string(cs.centerChannel) + " " + std::to_string(cs.bandwidthMHz) +
         "MHz (" + hex16(cs.raw) + ")\n";
    s += "\tPrimary channel: " + std::to_string(cs.controlChannel()) + "\n";
    s += "\tHT Capabilities: " + std::string(cs.bandwidthMHz >= 40 ? "40Mhz " : "") +
         "SGI20 SGI40 \n\tSupported HT MCS : 0-31\n";
    if (cs.bandwidthMHz >= 80) s += "\tVHT Capabilities: SGI80 \n";
    return s + "\n";
}

std::string bytesToFirmwareError(const std::string& why, const std::string& cmd)
{
    return "nexutil: ioctl " + cmd + " failed: " + why;
}
}  // namespace

const char* toString(DriverModule m)
{
    switch (m)
    {
        case DriverModule::Stock:
            return "stock";
        case DriverModule::None:
            return "none";
        case DriverModule::NexmonCsi:
            return "nexmon_csi";
    }
    return "?";
}

const char* toString(SilenceReason r)
{
    switch (r)
    {
        case SilenceReason::None:
            return "none";
        case SilenceReason::Rebooting:
            return "rebooting";
        case SilenceReason::StockFirmware:
            return "stock firmware (CSI module not loaded)";
        case SilenceReason::ModuleNotLoaded:
            return "driver module not loaded";
        case SilenceReason::InterfaceDown:
            return "interface down";
        case SilenceReason::RadioOff:
            return "radio off";
        case SilenceReason::NotBridged:
            return "interface not in br0";
        case SilenceReason::MonitorOff:
            return "monitor mode off";
        case SilenceReason::CsiNotConfigured:
            return "CSI not configured";
        case SilenceReason::CsiDisabled:
            return "CSI collection disabled";
        case SilenceReason::Retuning:
            return "retuning";
        case SilenceReason::Scanning:
            return "scanning";
    }
    return "?";
}

const char* toString(RouterKind k)
{
    return k == RouterKind::RaspberryPi ? "raspberry-pi" : "rt-ac86u";
}

RouterModel::RouterModel(RouterTiming timing, RouterKind kind) : timing_(timing), kind_(kind)
{
    if (kind_ == RouterKind::RaspberryPi) module_ = DriverModule::NexmonCsi;
    resetInterfaces(true);
}

void RouterModel::resetInterfaces(bool bridged)
{
    interfaces_.clear();
    if (kind_ == RouterKind::RaspberryPi)
    {
        WirelessInterface wlan0;
        wlan0.name = "wlan0";
        wlan0.band = WifiBand::Band5G;
        wlan0.dualBand = true;
        wlan0.chanspec = Chanspec::make(36, 20);
        interfaces_ = {wlan0};
        return;
    }
    WirelessInterface eth5;
    eth5.name = "eth5";
    eth5.band = WifiBand::Band2G4;
    eth5.chanspec = Chanspec::make(6, 20);
    eth5.bridged = bridged;
    WirelessInterface eth6;
    eth6.name = "eth6";
    eth6.band = WifiBand::Band5G;
    eth6.chanspec = Chanspec::fromString("100/80");  // control 100, centre 106 (0xe06a)
    eth6.bridged = bridged;
    interfaces_ = {eth5, eth6};
}

WirelessInterface* RouterModel::mutableInterface(const std::string& name)
{
    for (auto& i : interfaces_)
        if (i.name == name) return &i;
    return nullptr;
}

const WirelessInterface* RouterModel::findInterface(const std::string& name) const
{
    for (const auto& i : interfaces_)
        if (i.name == name) return &i;
    return nullptr;
}

void RouterModel::reboot(double now_s)
{
    // The Pi's patched firmware is installed on its SD card: it comes back with every boot.
    module_ = kind_ == RouterKind::RaspberryPi ? DriverModule::NexmonCsi : DriverModule::Stock;
    resetInterfaces(true);  // the stock setup bridges the radios
    bootDoneAt_s_ = now_s + timing_.rebootDuration_s;
    ++bootCount_;
    ++generation_;
}

void RouterModel::preconfigure(const Chanspec& cs, double now_s)
{
    module_ = DriverModule::NexmonCsi;
    resetInterfaces(false);
    WirelessInterface& itf = kind_ == RouterKind::RaspberryPi
                                 ? interfaces_.front()
                                 : *mutableInterface(cs.band == WifiBand::Band5G ? "eth6" : "eth5");
    itf.bridged = true;
    itf.monitor = true;
    if (itf.dualBand)
    {
        itf.band = cs.band;
        itf.monitorInterface = "mon0";
        itf.monitorInterfaceUp = true;
    }
    itf.chanspec = cs;
    CsiParams p;
    p.chanspecWord = cs.raw;
    p.collect = true;
    p.coreMask = kind_ == RouterKind::RaspberryPi ? 0x01 : 0x0F;
    p.nssMask = kind_ == RouterKind::RaspberryPi ? 0x01 : 0x0F;
    p.delay_us = kDefaultBusyDelay_us;
    itf.csi = p;
    bootDoneAt_s_ = std::min(bootDoneAt_s_, now_s);
    ++generation_;
}

SilenceReason RouterModel::silenceReason(const WirelessInterface& itf, double now_s) const
{
    if (rebooting(now_s)) return SilenceReason::Rebooting;
    if (module_ == DriverModule::None || !itf.present) return SilenceReason::ModuleNotLoaded;
    if (module_ == DriverModule::Stock) return SilenceReason::StockFirmware;
    if (!itf.up) return SilenceReason::InterfaceDown;
    if (!itf.radioOn) return SilenceReason::RadioOff;
    if (!itf.csi) return SilenceReason::CsiNotConfigured;
    if (!itf.csi->collect) return SilenceReason::CsiDisabled;
    if (timing_.requireMonitorMode && !itf.monitor) return SilenceReason::MonitorOff;
    if (!itf.bridged) return SilenceReason::NotBridged;
    if (now_s < itf.retuneUntil_s) return SilenceReason::Retuning;
    if (timing_.scanInterruptsCsi && now_s < itf.scanUntil_s) return SilenceReason::Scanning;
    return SilenceReason::None;
}

std::vector<ActiveCapture> RouterModel::activeCaptures(double now_s) const
{
    std::vector<ActiveCapture> out;
    for (const auto& itf : interfaces_)
        if (silenceReason(itf, now_s) == SilenceReason::None)
            out.push_back({itf.name, itf.chanspec, *itf.csi});
    return out;
}

double RouterModel::nextTimedChange(double now_s) const
{
    double t = kInf;
    auto consider = [&](double when)
    {
        if (when > now_s) t = std::min(t, when);
    };
    consider(bootDoneAt_s_);
    for (const auto& itf : interfaces_)
    {
        consider(itf.retuneUntil_s);
        consider(itf.scanUntil_s);
    }
    return t;
}

void RouterModel::tune(WirelessInterface& itf, const Chanspec& cs, double now_s)
{
    if (itf.chanspec == cs) return;
    itf.chanspec = cs;
    itf.retuneUntil_s = now_s + timing_.retuneDelay_s;
}

ToolResult RouterModel::execute(const Argv& argv, double now_s)
{
    if (argv.empty()) return ToolResult::failure("sh: empty command", 127);
    if (rebooting(now_s))
        return ToolResult::failure(
            "ssh: connect to host router port 22: Connection refused (rebooting)",
            kUnreachableExitCode);
    const std::string tool = baseName(argv[0]);
    const Argv args(argv.begin() + 1, argv.end());
    ToolResult r;
    static const std::set<std::string> piTools = {"nexutil", "makecsiparams", "ifconfig", "ip",
                                                  "iw",      "lsmod"};
    if (kind_ == RouterKind::RaspberryPi && !piTools.count(tool))
        r = ToolResult::failure("sh: " + tool + ": not found", 127);
    else if (tool == "ip")
        r = ip(args);
    else if (tool == "iw")
        r = iw(args);
    else if (tool == "wl")
        r = wl(args, now_s);
    else if (tool == "nexutil")
        r = nexutil(args, now_s);
    else if (tool == "makecsiparams")
        r = makeCsiParams(args);
    else if (tool == "insmod")
        r = insmod(args);
    else if (tool == "rmmod")
        r = rmmod(args);
    else if (tool == "lsmod")
        r = lsmod(args);
    else if (tool == "brctl")
        r = brctl(args);
    else if (tool == "ifconfig")
        r = ifconfig(args);
    else
        r = ToolResult::failure("sh: " + tool + ": not found", 127);
    ++commandsExecuted_;
    if (r.exitCode != 0) ++commandsFailed_;
    ++generation_;
    return r;
}

// ---------------------------------------------------------------------------------------- wl
ToolResult RouterModel::wl(const Argv& argsIn, double now_s)
{
    Argv args = argsIn;
    std::string ifname = kDefaultWlInterface;
    if (!args.empty() && (args[0] == "-i" || args[0] == "-a"))
    {
        if (args.size() < 2)
            return ToolResult::failure("wl: missing adapter name after " + args[0]);
        ifname = args[1];
        args.erase(args.begin(), args.begin() + 2);
    }
    else if (!args.empty() && args[0].size() > 2 && (args[0].rfind("-i", 0) == 0))
    {
        ifname = args[0].substr(2);
        args.erase(args.begin());
    }
    if (args.empty())
        return ToolResult::failure(
            "Usage: wl [-a|i <adapter>] <command> [arguments]\n"
            "emulated commands: chanspec monitor up down isup radio country scan scanresults "
            "5g_rate 2g_rate ver");
    WirelessInterface* itf = mutableInterface(ifname);
    if (module_ == DriverModule::None || !itf || !itf->present)
        return ToolResult::failure("wl: wl driver adapter not found");

    const std::string cmd = args[0];
    const Argv rest(args.begin() + 1, args.end());
    auto boolArg = [](const std::string& s, bool& out)
    {
        unsigned long v = 0;
        if (s == "on")
            v = 1;
        else if (s == "off")
            v = 0;
        else if (!parseUnsigned(s, 0xFFFFFFFF, v))
            return false;
        out = v != 0;
        return true;
    };

    if (cmd == "chanspec")
    {
        if (rest.empty())
            return ToolResult::success(  // Broadcom notation, like the real wl: "157/80 (0xe29b)"
                itf->chanspec.asBroadcomString() + " (" + hex16(itf->chanspec.raw) + ")\n");
        if (rest.size() > 1) return ToolResult::failure("wl: Bad Argument");
        Chanspec cs;
        try
        {
            cs = parseRouterChanspec(rest[0]);
        }
        catch (const std::invalid_argument&)
        {
            return ToolResult::failure("wl: Bad Chanspec '" + rest[0] + "'");
        }
        if (cs.band != itf->band) return ToolResult::failure("wl: Bad Channel");
        tune(*itf, cs, now_s);
        return ToolResult::success();
    }
    if (cmd == "monitor")
    {
        if (rest.empty()) return ToolResult::success(itf->monitor ? "1\n" : "0\n");
        bool on = false;
        if (rest.size() > 1 || !boolArg(rest[0], on))
            return ToolResult::failure("wl: Bad Argument");
        itf->monitor = on;
        return ToolResult::success();
    }
    if (cmd == "up" || cmd == "down")
    {
        if (!rest.empty()) return ToolResult::failure("wl: Bad Argument");
        itf->up = cmd == "up";
        return ToolResult::success();
    }
    if (cmd == "isup")
        return rest.empty() ? ToolResult::success(itf->up ? "1\n" : "0\n")
                            : ToolResult::failure("wl: Bad Argument");
    if (cmd == "radio")
    {
        if (rest.empty()) return ToolResult::success(itf->radioOn ? "0x0000\n" : "0x0001\n");
        bool on = false;
        if (rest.size() > 1 || !boolArg(rest[0], on))
            return ToolResult::failure("wl: Bad Argument");
        itf->radioOn = on;
        return ToolResult::success();
    }
    if (cmd == "country")
    {
        if (rest.empty()) return ToolResult::success(itf->country + " (" + itf->country + "/0)\n");
        if (rest.size() > 1 || rest[0].size() < 2 || rest[0].size() > 3)
            return ToolResult::failure("wl: Bad Argument");
        itf->country = rest[0];
        return ToolResult::success();
    }
    if (cmd == "scan")
    {
        if (!rest.empty())
            return ToolResult::failure("wl: Bad Argument (emulated: plain 'wl scan')");
        if (!itf->up || !itf->radioOn) return ToolResult::failure("wl: Not Ready");
        // Results are what the radio hears when the scan starts (the robot barely moves in 1 s).
        itf->scanResults.clear();
        if (scanProvider_)
            for (auto& e : scanProvider_(itf->band))
                if (e.chanspec.band == itf->band) itf->scanResults.push_back(e);
        itf->scanUntil_s = now_s + timing_.scanDuration_s;
        itf->scanDone = true;
        return ToolResult::success();
    }
    if (cmd == "scanresults")
    {
        if (!rest.empty()) return ToolResult::failure("wl: Bad Argument");
        if (now_s < itf->scanUntil_s) return ToolResult::failure("wl: Not Ready");
        std::string out;
        if (itf->scanDone)
            for (const auto& e : itf->scanResults) out += formatScanEntry(e, itf->chanspec);
        return ToolResult::success(out);
    }
    if (cmd == "5g_rate" || cmd == "2g_rate")
    {
        // Transmit rate of injected frames (transmitter mode): -v MCS -s NSS [-b BW] ... | auto
        std::string& rate = cmd == "5g_rate" ? itf->rate5G : itf->rate2G4;
        if (rest.empty()) return ToolResult::success(rate + "\n");
        if (rest.size() == 1 && rest[0] == "auto")
        {
            rate = "auto";
            return ToolResult::success();
        }
        static const std::set<std::string> kWithValue = {"-r", "-h", "-v", "-s", "-b", "-x", "-e"},
                                           kFlags = {"-l", "-g", "-i", "--ldpc", "--stbc", "--sgi"};
        std::string text;
        for (size_t i = 0; i < rest.size(); ++i)
        {
            const std::string& a = rest[i];
            unsigned long v = 0;
            if (kWithValue.count(a))
            {
                if (i + 1 >= rest.size() || !parseUnsigned(rest[i + 1], 1000, v))
                    return ToolResult::failure("wl: Bad Argument (" + cmd + " " + a + ")");
                if (a == "-s" && (v < 1 || v > 4))
                    return ToolResult::failure("wl: Bad Argument (" + cmd + " -s: 1..4 streams)");
                text += (text.empty() ? "" : " ") + a + " " + rest[++i];
            }
            else if (kFlags.count(a))
                text += (text.empty() ? "" : " ") + a;
            else
                return ToolResult::failure("wl: Bad Argument (" + cmd + " '" + a + "')");
        }
        rate = text;
        return ToolResult::success();
    }
    if (cmd == "ver")
        return ToolResult::success(
            "10.10.122.20 (emulated RT-AC86U, BCM4366c0, Nexmon CSI)\nwl0: Oct 1 2018 "
            "version 10.10.122.20 (r683106) FWID 01-ffffffff\n");
    return ToolResult::failure("wl: Unsupported (unknown or not emulated command '" + cmd + "')");
}

// ----------------------------------------------------------------------------------- nexutil
ToolResult RouterModel::nexutil(const Argv& args, double now_s)
{
    static const char* kUsage =
        "Usage: nexutil [-I IFACE] (-s CMD | -g CMD) [-b] [-l LEN] [-v VALUE | -i INT]\n"
        "  -s500 -b -l34 -v BASE64    set the CSI extraction parameters (makecsiparams)\n"
        "  -s505 -b -l LEN -v BASE64  inject a frame (transmitter / beacon mode)\n";
    ShortOptionParser opts(args, "hI:s:g:l:v:bi:r");
    std::string ifname = kind_ == RouterKind::RaspberryPi ? "wlan0" : kDefaultNexutilInterface,
                setCmd, getCmd, value, lenText;
    bool base64 = false, integer = false;
    char o;
    std::string v;
    while (opts.next(o, v))
    {
        switch (o)
        {
            case 'h':
                return ToolResult::success(kUsage);
            case 'I':
                ifname = v;
                break;
            case 's':
                setCmd = v;
                break;
            case 'g':
                getCmd = v;
                break;
            case 'l':
                lenText = v;
                break;
            case 'v':
                value = v;
                break;
            case 'b':
                base64 = true;
                break;
            case 'i':
                integer = true;
                value = v;
                break;
            case 'r':
                break;
        }
    }
    if (!opts.error().empty())
        return ToolResult::failure("nexutil: " + opts.error() + "\n" + kUsage);
    if (!opts.remaining().empty())
        return ToolResult::failure("nexutil: unexpected argument '" + opts.remaining()[0] + "'");
    if (setCmd.empty() && getCmd.empty()) return ToolResult::failure(kUsage);

    WirelessInterface* itf = mutableInterface(ifname);
    if (module_ == DriverModule::None || !itf || !itf->present)
        return ToolResult::failure("nexutil: cannot open interface " + ifname + ": No such device");
    const std::string cmdText = setCmd.empty() ? getCmd : setCmd;
    if (module_ != DriverModule::NexmonCsi)
        return ToolResult::failure(bytesToFirmwareError(
            "Unsupported (stock firmware; the Nexmon dhd.ko is not loaded)", cmdText));
    if (!getCmd.empty()) return ToolResult::failure(bytesToFirmwareError("Unsupported", getCmd));

    unsigned long cmd = 0, len = 0;
    if (!parseUnsigned(setCmd, 0xFFFF, cmd))
        return ToolResult::failure("nexutil: invalid ioctl number '" + setCmd + "'");
    if (lenText.empty()) return ToolResult::failure("nexutil: -s needs a length (-l)");
    if (!parseUnsigned(lenText, 1 << 20, len))
        return ToolResult::failure("nexutil: invalid length '" + lenText + "'");
    if (value.empty()) return ToolResult::failure("nexutil: -s needs a value (-v)");
    if (integer || !base64)
        return ToolResult::failure(bytesToFirmwareError("Bad Length (expected -b BASE64)", setCmd));
    const auto bytes = base64Decode(value);
    if (!bytes) return ToolResult::failure("nexutil: invalid base64 value");
    if (bytes->size() != len)
        return ToolResult::failure(
            "nexutil: value is " + std::to_string(bytes->size()) + " bytes but -l says " +
            std::to_string(len));

    if (cmd == 500) return applyCsiParams(*itf, *bytes, now_s);
    if (cmd == 505)
    {
        if (len < kMinInjectedFrame || len > kMaxInjectedFrame)
            return ToolResult::failure(bytesToFirmwareError("Bad Length", setCmd));
        if (!itf->up || !itf->radioOn)
            return ToolResult::failure(bytesToFirmwareError("Not Up", setCmd));
        ++itf->framesInjected;
        itf->lastInjectedLength = len;
        itf->lastInjection_s = now_s;
        return ToolResult::success();
    }
    return ToolResult::failure(bytesToFirmwareError("Unsupported", setCmd));
}

ToolResult RouterModel::applyCsiParams(
    WirelessInterface& itf, const std::vector<uint8_t>& bytes, double now_s)
{
    if (bytes.size() != kCsiParamsBytes)
        return ToolResult::failure(bytesToFirmwareError("Bad Length", "500"));
    CsiParams p;
    try
    {
        p = CsiParams::fromBytes(bytes.data(), bytes.size());
    }
    catch (const std::invalid_argument&)
    {
        return ToolResult::failure(bytesToFirmwareError("Bad Argument", "500"));
    }
    if (p.collect)
    {
        const auto cs = p.chanspec();
        // The Pi's 43455c0 does 20/40/80 MHz on 5 GHz, 20 MHz on 2.4 GHz (nexmon_csi).
        const bool piOk = !cs || !itf.dualBand ||
                          (cs->bandwidthMHz <= (cs->band == WifiBand::Band5G ? 80u : 20u));
        if (!cs || (cs->band != itf.band && !itf.dualBand) || !piOk)
            return ToolResult::failure(bytesToFirmwareError("Bad Channel", "500"));
        if (itf.dualBand) itf.band = cs->band;
        if (!p.coreMask || !p.nssMask)
            return ToolResult::failure(bytesToFirmwareError("Bad Argument", "500"));
        tune(itf, *cs, now_s);  // the firmware tunes the radio to the requested chanspec
    }
    itf.csi = p;
    return ToolResult::success();
}

// ------------------------------------------------------------------------ modules and bridge
ToolResult RouterModel::insmod(const Argv& args)
{
    if (args.empty()) return ToolResult::failure("Usage: insmod FILE [SYMBOL=VALUE]...");
    const std::string& path = args[0];
    if (baseName(path) != "dhd.ko")
        return ToolResult::failure(
            "insmod: can't read '" + path + "': No such file or directory (emulated: only dhd.ko)");
    if (module_ != DriverModule::None)
        return ToolResult::failure("insmod: can't insert '" + path + "': File exists");
    module_ = DriverModule::NexmonCsi;
    resetInterfaces(false);  // fresh interfaces, outside the bridge
    return ToolResult::success();
}

ToolResult RouterModel::rmmod(const Argv& args)
{
    if (args.empty()) return ToolResult::failure("Usage: rmmod MODULE...");
    for (const auto& name : args)
    {
        if ((name != "dhd" && name != "dhd.ko") || module_ == DriverModule::None)
            return ToolResult::failure(
                "rmmod: can't unload module '" + name + "': No such file or directory");
        module_ = DriverModule::None;
        for (auto& itf : interfaces_)
        {
            itf.present = false;
            itf.bridged = false;
            itf.csi.reset();
        }
    }
    return ToolResult::success();
}

ToolResult RouterModel::lsmod(const Argv& args) const
{
    if (!args.empty()) return ToolResult::failure("Usage: lsmod");
    std::string out = "Module                  Size  Used by\n";
    if (module_ == DriverModule::NexmonCsi) out += "dhd                  1351380  0 \n";
    if (module_ == DriverModule::Stock) out += "dhd                  1350972  0 \n";
    return ToolResult::success(out);
}

ToolResult RouterModel::brctl(const Argv& args)
{
    if (args.empty())
        return ToolResult::failure("Usage: brctl COMMAND [BRIDGE] [IFACE]\n  addif delif show");
    const std::string& cmd = args[0];
    if (cmd == "show")
    {
        std::string out =
            "bridge name\tbridge id\t\tSTP enabled\tinterfaces\nbr0\t\t8000.000000000000\tno\t\t";
        bool first = true;
        for (const auto& itf : interfaces_)
            if (itf.present && itf.bridged)
            {
                out += (first ? "" : "\n\t\t\t\t\t\t\t") + itf.name;
                first = false;
            }
        return ToolResult::success(out + "\n");
    }
    if (cmd != "addif" && cmd != "delif")
        return ToolResult::failure("brctl: unknown command '" + cmd + "'");
    if (args.size() != 3) return ToolResult::failure("Usage: brctl " + cmd + " BRIDGE IFACE");
    if (args[1] != kBridge) return ToolResult::failure("bridge " + args[1] + " does not exist!");
    WirelessInterface* itf = mutableInterface(args[2]);
    if (!itf || !itf->present)
        return ToolResult::failure("interface " + args[2] + " does not exist!");
    if (cmd == "addif")
    {
        if (itf->bridged)
            return ToolResult::failure(
                "device " + itf->name +
                " is already a member of a bridge; can't enslave it to "
                "bridge br0.");
        itf->bridged = true;
    }
    else
    {
        if (!itf->bridged)
            return ToolResult::failure("device " + itf->name + " is not a slave of br0");
        itf->bridged = false;
    }
    return ToolResult::success();
}

WirelessInterface* RouterModel::interfaceOrMonitor(const std::string& name, bool* monitor)
{
    *monitor = false;
    if (auto* itf = mutableInterface(name); itf && itf->present) return itf;
    for (auto& itf : interfaces_)
        if (itf.present && !itf.monitorInterface.empty() && itf.monitorInterface == name)
        {
            *monitor = true;
            return &itf;
        }
    return nullptr;
}

ToolResult RouterModel::ifconfig(const Argv& args)
{
    if (args.empty()) return ToolResult::failure("Usage: ifconfig IFACE [up|down]");
    bool monitor = false;
    WirelessInterface* itf = interfaceOrMonitor(args[0], &monitor);
    if (!itf)
        return ToolResult::failure(
            "ifconfig: " + args[0] + ": error fetching interface information: Device not found");
    bool& up = monitor ? itf->monitorInterfaceUp : itf->up;
    if (args.size() == 1)
        return ToolResult::success(
            args[0] + "      Link encap:Ethernet\n          " +
            (up ? "UP BROADCAST RUNNING MULTICAST" : "BROADCAST MULTICAST") + "\n");
    if (args.size() != 2 || (args[1] != "up" && args[1] != "down"))
        return ToolResult::failure("ifconfig: emulated: only 'ifconfig IFACE up|down'");
    up = args[1] == "up";
    if (monitor) itf->monitor = itf->monitorInterfaceUp;
    return ToolResult::success();
}

ToolResult RouterModel::ip(const Argv& args)
{
    // iproute2's `ip link set DEV up|down` and `ip link show [DEV]`.
    const char* usage = "Usage: ip link set DEV up|down | ip link show [DEV] (emulated)";
    if (args.size() < 2 || (args[0] != "link" && args[0] != "l"))
        return ToolResult::failure(usage, 255);
    bool monitor = false;
    if (args[1] == "show" && args.size() <= 3)
    {
        std::string out;
        int index = 2;
        for (const auto& itf : interfaces_)
        {
            if (!itf.present) continue;
            const auto line = [&](const std::string& name, bool up, bool mon)
            {
                out += std::to_string(++index) + ": " + name + ": <BROADCAST,MULTICAST" +
                       (up ? ",UP,LOWER_UP" : "") + "> mtu 1500 state " + (up ? "UP" : "DOWN") +
                       "\n    link/" + (mon ? "ieee802.11/radiotap" : "ether") + "\n";
            };
            if (args.size() == 2 || args[2] == itf.name) line(itf.name, itf.up, false);
            if (!itf.monitorInterface.empty() &&
                (args.size() == 2 || args[2] == itf.monitorInterface))
                line(itf.monitorInterface, itf.monitorInterfaceUp, true);
        }
        if (out.empty())
            return ToolResult::failure("Device \"" + args[2] + "\" does not exist.", 1);
        return ToolResult::success(out);
    }
    if (args[1] != "set" || args.size() != 4 || (args[3] != "up" && args[3] != "down"))
        return ToolResult::failure(usage, 255);
    WirelessInterface* itf = interfaceOrMonitor(args[2], &monitor);
    if (!itf) return ToolResult::failure("Cannot find device \"" + args[2] + "\"", 1);
    (monitor ? itf->monitorInterfaceUp : itf->up) = args[3] == "up";
    if (monitor) itf->monitor = itf->monitorInterfaceUp;
    return ToolResult::success();
}

ToolResult RouterModel::iw(const Argv& args)
{
    // `iw dev` (list), `iw dev DEV interface add NAME type monitor`, `iw dev NAME del`.
    const char* usage =
        "Usage: iw dev | iw dev DEV interface add NAME type monitor | iw dev NAME del (emulated)";
    if (args.empty() || args[0] != "dev") return ToolResult::failure(usage, 1);
    if (args.size() == 1)
    {
        std::string out = "phy#0\n";
        for (const auto& itf : interfaces_)
        {
            if (!itf.present) continue;
            if (!itf.monitorInterface.empty())
                out += "\tInterface " + itf.monitorInterface + "\n\t\ttype monitor\n";
            out += "\tInterface " + itf.name + "\n\t\ttype managed\n\t\tchannel " +
                   std::to_string(itf.chanspec.controlChannel()) +
                   ", width: " + std::to_string(itf.chanspec.bandwidthMHz) + " MHz\n";
        }
        return ToolResult::success(out);
    }
    bool monitor = false;
    WirelessInterface* itf = interfaceOrMonitor(args[1], &monitor);
    if (!itf) return ToolResult::failure("command failed: No such device (-19)", 237);
    if (args.size() == 3 && args[2] == "del" && monitor)
    {
        itf->monitorInterface.clear();
        itf->monitorInterfaceUp = itf->monitor = false;
        return ToolResult::success();
    }
    if (args.size() == 7 && !monitor && args[2] == "interface" && args[3] == "add" &&
        args[5] == "type" && args[6] == "monitor")
    {
        const std::string& name = args[4];
        if (name.empty() || name.size() > 15 || mutableInterface(name) ||
            !itf->monitorInterface.empty())
            return ToolResult::failure("command failed: Too many open files in system (-23)", 233);
        itf->monitorInterface = name;
        itf->monitorInterfaceUp = itf->monitor = false;  // created down, as the kernel does
        return ToolResult::success();
    }
    return ToolResult::failure(usage, 1);
}

// ---------------------------------------------------------------------------------- status
std::string RouterModel::toJson(double now_s) const
{
    std::vector<std::string> itfs;
    for (const auto& itf : interfaces_)
    {
        JsonObject j;
        j.str("name", itf.name)
            .str("band", itf.band == WifiBand::Band5G ? "5GHz" : "2.4GHz")
            .boolean("present", itf.present)
            .boolean("up", itf.up)
            .boolean("radio_on", itf.radioOn)
            .boolean("monitor", itf.monitor)
            .boolean("bridged", itf.bridged)
            .str("monitor_interface", itf.monitorInterface)
            .str("chanspec", itf.chanspec.asString())
            .str("chanspec_word", hex16(itf.chanspec.raw));
        if (itf.csi)
        {
            const auto& p = *itf.csi;
            std::vector<std::string> macs;
            for (const auto& m : p.macFilter) macs.push_back(jsonQuote(m.asString()));
            JsonObject c;
            c.boolean("collect", p.collect)
                .str("chanspec", p.chanspec() ? p.chanspec()->asString() : std::string())
                .uint("core_mask", p.coreMask)
                .uint("nss_mask", p.nssMask)
                .raw("mac_filter", detail::jsonArray(macs))
                .boolean("packet_filter", p.usePacketFilter)
                .uint("first_packet_byte", p.firstPacketByte)
                .uint("delay_us", p.delay_us);
            j.raw("csi", c.json());
        }
        else
            j.raw("csi", "null");
        j.str("silence_reason", toString(silenceReason(itf, now_s)))
            .boolean("scanning", now_s < itf.scanUntil_s)
            .uint("scan_results", itf.scanResults.size())
            .str("rate", itf.band == WifiBand::Band5G ? itf.rate5G : itf.rate2G4)
            .uint("frames_injected", itf.framesInjected)
            .uint("last_injected_length", itf.lastInjectedLength)
            .num("last_injection_age_s", now_s - itf.lastInjection_s);
        itfs.push_back(j.json());
    }
    JsonObject r;
    r.str("device", toString(kind_))
        .uint("boot", bootCount_)
        .boolean("rebooting", rebooting(now_s))
        .str("module", toString(module_))
        .uint("commands", commandsExecuted_)
        .uint("commands_failed", commandsFailed_)
        .raw("interfaces", detail::jsonArray(itfs));
    return r.json();
}

}  // namespace mrpt_wifi::emulator
