/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/sensor/NexmonPiControl.h>
#include <mrpt_wifi/sensor/Subprocess.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

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

std::string joined(const std::vector<std::string>& argv)
{
    std::string s;
    for (const auto& a : argv) s += (s.empty() ? "" : " ") + shellQuote(a);
    return s;
}

std::string withToolDir(const std::string& dir, const std::string& program)
{
    return dir.empty() ? program : (std::filesystem::path(dir) / program).string();
}

std::string firstLine(const std::string& s)
{
    return s.substr(0, s.find('\n'));
}

bool isBase64(const std::string& s)
{
    return !s.empty() && s.size() % 4 == 0 &&
           std::all_of(
               s.begin(), s.end(),
               [](char c)
               {
                   return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') ||
                          (c >= '0' && c <= '9') || c == '+' || c == '/' || c == '=';
               });
}
}  // namespace

std::string LocalCommandRunner::run(const std::vector<std::string>& argvIn, double timeout_s)
{
    auto argv = argvIn;
    argv.at(0) = withToolDir(toolDir_, argv[0]);
    const auto r = runSubprocess(argv, timeout_s);
    if (r.exitCode == 0 && !r.timedOut) return r.out;
    // Locally, exit 255 is the program's own (no ssh in between): not "unreachable".
    SubprocessResult classified = r;
    if (classified.exitCode == 255) classified.exitCode = 1;
    const auto kind = r.exitCode == 127 && r.err.find("exec failed") != std::string::npos
                          ? RouterErrorKind::CommandMissing
                          : classifyRouterFailure(classified);
    std::string detail = firstLine(r.err.empty() ? r.out : r.err);
    if (r.timedOut) detail = "no answer within " + std::to_string(timeout_s) + " s";
    if (kind == RouterErrorKind::CommandMissing) detail = argv[0] + " not found";
    throw RouterError(
        kind, describe() + ": '" + joined(argv) + "' (exit " + std::to_string(r.exitCode) +
                  "): " + detail);
}

std::string LocalCommandRunner::describe() const
{
    return "this machine" + (toolDir_.empty() ? std::string() : " (tools in " + toolDir_ + ")");
}

std::string ShellCommandRunner::run(const std::vector<std::string>& argvIn, double timeout_s)
{
    auto argv = argvIn;
    argv.at(0) = withToolDir(toolDir_, argv[0]);
    return shell_->run(joined(argv), timeout_s);
}

void PiSetupOptions::validate() const
{
    const auto nameOk = [](const std::string& s)
    {
        return !s.empty() && s.size() <= 15 &&
               std::all_of(
                   s.begin(), s.end(),
                   [](char c)
                   {
                       return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                              (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
                   });
    };
    if (!nameOk(interface))
        throw std::invalid_argument(
            "key 'pi_interface': '" + interface +
            "' is not an interface name ([A-Za-z0-9_.-], 1..15 characters)");
    if (!monitorInterface.empty() && (!nameOk(monitorInterface) || monitorInterface == interface))
        throw std::invalid_argument(
            "key 'pi_monitor_interface': '" + monitorInterface +
            "' is not an interface name ([A-Za-z0-9_.-], 1..15 characters, not pi_interface)");
    if (!toolDir.empty() && (toolDir[0] != '/' || shellQuote(toolDir) != toolDir))
        throw std::invalid_argument(
            "key 'pi_tool_dir': '" + toolDir +
            "' is not an absolute path of [A-Za-z0-9_./+@%:,=-] characters");
    if (!(commandTimeout_s > 0)) throw std::invalid_argument("key 'command_timeout' must be > 0");
}

void validatePiExtraction(const CsiExtractionSettings& s)
{
    const Chanspec& cs = s.chanspec;
    // A channel of the 5 GHz plan up to 165 (the 43455c0's) whose 20/40/80 MHz block exists:
    // 36/80 yes, 50/80 and 165/80 (169..177, U-NII-4) no.
    const unsigned control = cs.controlChannel();
    const bool in5GPlan = (control >= 36 && control <= 64) || (control >= 100 && control <= 144) ||
                          (control >= 149 && control <= 165);
    const auto block = Chanspec::fromControlChannel(control, cs.bandwidthMHz);
    if (cs.band == WifiBand::Band5G && (!in5GPlan || control % 4 != (control >= 149 ? 1u : 0u) ||
                                        !block || block->centerChannel != cs.centerChannel ||
                                        cs.centerChannel + 2 * (cs.bandwidthMHz / 20 - 1) > 165))
        throw std::invalid_argument(
            "key 'channel': " + cs.asString() + " is not a 5 GHz channel of " +
            std::to_string(cs.bandwidthMHz) + " MHz (e.g. 36/20, 38/40, 42/80, 155/80)");
    const unsigned maxBw = cs.band == WifiBand::Band5G ? 80 : 20;
    if (cs.bandwidthMHz > maxBw)
        throw std::invalid_argument(
            "key 'channel': " + cs.asString() +
            " is not valid for the Raspberry Pi's bcm43455c0 (" + std::to_string(cs.bandwidthMHz) +
            " MHz; it captures 20/40/80 MHz on 5 GHz, 20 MHz "
            "on 2.4 GHz)");
    if (s.coreMask != 0x1)
        throw std::invalid_argument(
            "key 'core_mask': " + hexByte(s.coreMask) +
            " (the Raspberry Pi's bcm43455c0 has one core: 0x1)");
    if (s.streamMask != 0x1)
        throw std::invalid_argument(
            "key 'stream_mask': " + hexByte(s.streamMask) +
            " (the Raspberry Pi's bcm43455c0 reports one stream: 0x1)");
    if (s.macFilter.size() > 4)
        throw std::invalid_argument("key 'packet_mac_filter': the firmware takes at most 4 MACs");
}

NexmonPiControl::NexmonPiControl(std::shared_ptr<CommandRunner> runner, PiSetupOptions options)
    : runner_(std::move(runner)), options_(std::move(options))
{
    options_.validate();
}

std::vector<std::string> NexmonPiControl::makeCsiParamsArgv(const CsiExtractionSettings& s) const
{
    std::vector<std::string> a = {"makecsiparams",     "-c", s.chanspec.asBroadcomString(), "-C",
                                  hexByte(s.coreMask), "-N", hexByte(s.streamMask)};
    if (!s.macFilter.empty())
    {
        std::string macs;
        for (const auto& m : s.macFilter) macs += (macs.empty() ? "" : ",") + m.asString();
        a.insert(a.end(), {"-m", macs});
    }
    if (s.delay) a.insert(a.end(), {"-d", std::to_string(s.delay)});
    if (s.firstPacketByte) a.insert(a.end(), {"-b", hexByte(*s.firstPacketByte)});
    return a;
}

std::vector<std::vector<std::string>> NexmonPiControl::configureCommands(
    const CsiExtractionSettings& s) const
{
    const auto& itf = options_.interface;
    std::vector<std::vector<std::string>> c = {
        {"ip", "link", "set", itf, "up"},
        makeCsiParamsArgv(s),
        {"nexutil", "-I" + itf, "-s500", "-b", "-l34", "-v<params>"}};
    if (!options_.monitorInterface.empty())
    {
        const auto& mon = options_.monitorInterface;
        c.push_back({"iw", "dev", itf, "interface", "add", mon, "type", "monitor"});
        c.push_back({"ip", "link", "set", mon, "up"});
    }
    return c;
}

void NexmonPiControl::configure(const CsiExtractionSettings& s)
{
    validatePiExtraction(s);
    const double t = options_.commandTimeout_s;
    const auto& itf = options_.interface;
    runner_->run({"ip", "link", "set", itf, "up"}, t);
    std::string params = runner_->run(makeCsiParamsArgv(s), t);
    params.erase(
        std::remove_if(
            params.begin(), params.end(), [](char c) { return std::isspace(uint8_t(c)); }),
        params.end());
    if (!isBase64(params))
        throw RouterError(
            RouterErrorKind::WrongFirmware, runner_->describe() + ": makecsiparams printed '" +
                                                firstLine(params) +
                                                "', not the base64 of the CSI parameters");
    runner_->run({"nexutil", "-I" + itf, "-s500", "-b", "-l34", "-v" + params}, t);
    if (options_.monitorInterface.empty()) return;
    const auto& mon = options_.monitorInterface;
    bool exists = true;
    try
    {
        runner_->run({"ip", "link", "show", mon}, t);
    }
    catch (const RouterError& e)
    {
        if (e.kind() == RouterErrorKind::Unreachable || e.kind() == RouterErrorKind::Timeout ||
            e.kind() == RouterErrorKind::AuthenticationFailed ||
            e.kind() == RouterErrorKind::HostKeyMismatch)
            throw;
        exists = false;  // "Device "mon0" does not exist."
    }
    if (!exists) runner_->run({"iw", "dev", itf, "interface", "add", mon, "type", "monitor"}, t);
    runner_->run({"ip", "link", "set", mon, "up"}, t);
}

}  // namespace mrpt_wifi
