/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * csi-router: configure, switch, scan and query an RT-AC86U running Nexmon CSI from a shell,
 * with the same .ini the CWiFiCSISensor driver reads. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/sensor/CsiSensorSettings.h>

#include <filesystem>
#include <iomanip>
#include <iostream>
#include <set>

using namespace mrpt_wifi;

namespace
{
struct FirstFrame
{
    std::optional<double> downtime;  //!< s from `start` to the first frame on the target
    uint64_t datagrams = 0;          //!< received meanwhile
    std::set<std::string> channels;  //!< of the frames received meanwhile
};

/** Waits for the first CSI frame on `target` arriving on the data path. */
FirstFrame waitFirstFrame(
    UdpCsiReceiver& rx, CsiFrameAssemblerOptions options, const Chanspec& target,
    mrpt::Clock::time_point start, double timeout_s)
{
    FirstFrame r;
    auto& downtime = r.downtime;
    CsiFrameAssembler assembler(
        options,
        [&](CObservationWiFiCSI::Ptr&& f)
        {
            r.channels.insert(f->chanspec.asString());
            if (!downtime && f->chanspec.sameChannel(target))
                downtime = std::chrono::duration<double>(f->timestamp - start).count();
        });
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (!downtime && std::chrono::steady_clock::now() < deadline)
    {
        rx.receive(
            [&](const uint8_t* d, size_t n, mrpt::Clock::time_point t, const std::string& src)
            {
                ++r.datagrams;
                assembler.push(d, n, t, src);
            },
            std::chrono::milliseconds(10));
        assembler.flushExpired(mrpt::Clock::now());
    }
    return r;
}
}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "csi-router",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Controls an Asus RT-AC86U running Nexmon CSI over ssh. Commands:\n"
                "  setup              load the patched firmware module (once per boot)\n"
                "  configure          tune to the .ini's channel and start CSI extraction\n"
                "  switch CH/BW       retune (157/80 or 155/80); --measure reports the downtime\n"
                "  scan               list access points (wl scan / scanresults)\n"
                "  status             the router's current chanspec\n"
                "  transmit start|stop  beacon injection (transmitter mode)\n"
                "Exit status: 0 done; 1 bad command line or .ini; 4 the router could not be "
                "controlled (ssh: connection refused, timed out, no route, authentication, host "
                "key, missing key file; or a router command failed: the message says which and "
                "what to check); switch --measure: 5 no datagram arrived, 6 datagrams but no CSI "
                "frame on the new channel. See docs/troubleshooting.md.",
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argCommand(
                "command", "setup|configure|switch|scan|status|transmit", true, "", "COMMAND", cmd);
            TCLAP::UnlabeledMultiArg<std::string> argArgs(
                "args", "Command arguments", false, "ARGS", cmd);
            TCLAP::ValueArg<std::string> argIni(
                "c", "config", "rawlog-grabber .ini with a CWiFiCSISensor section", false, "",
                "FILE.ini", cmd);
            TCLAP::ValueArg<std::string> argSection(
                "s", "section", "Section of the .ini", false, "WIFI_CSI", "NAME", cmd);
            TCLAP::ValueArg<std::string> argHost(
                "", "host", "Router address (overrides login_host)", false, "", "HOST", cmd);
            TCLAP::ValueArg<unsigned> argPort(
                "", "port", "ssh port (overrides login_port)", false, 0, "PORT", cmd);
            TCLAP::ValueArg<std::string> argUser(
                "", "user", "ssh user (overrides login_user)", false, "", "USER", cmd);
            TCLAP::ValueArg<std::string> argIdentity(
                "i", "identity", "ssh private key (overrides login_identity_file)", false, "",
                "FILE", cmd);
            TCLAP::ValueArg<std::string> argKnownHosts(
                "", "known-hosts", "known_hosts file (overrides login_known_hosts)", false, "",
                "FILE", cmd);
            TCLAP::SwitchArg argAcceptNew(
                "", "accept-new-host-key", "Trust a router never seen before", cmd);
            TCLAP::ValueArg<std::string> argPasswordEnv(
                "", "password-env",
                "NAME of an environment variable holding the password (never the password itself)",
                false, "", "NAME", cmd);
            TCLAP::SwitchArg argMeasure(
                "m", "measure",
                "switch: wait for the first CSI frame on the new channel and report the downtime",
                cmd);
            TCLAP::ValueArg<double> argTimeout(
                "", "measure-timeout", "switch --measure: seconds to wait", false, 3.0, "S", cmd);
            if (const int rc = cli::parseCommandLine(cmd, argc, const_cast<const char**>(argv));
                rc >= 0)
                return rc;

            const std::string section = argSection.getValue();
            std::unique_ptr<mrpt::config::CConfigFileBase> ini;
            if (argIni.isSet())
            {
                if (!std::filesystem::exists(argIni.getValue()))
                    throw std::runtime_error("config file '" + argIni.getValue() + "' not found");
                ini = std::make_unique<mrpt::config::CConfigFile>(argIni.getValue());
            }
            else
                ini = std::make_unique<mrpt::config::CConfigFileMemory>(
                    "[" + section + "]\nrouter_control = true\n");
            auto s = loadCsiSensorSettings(*ini, section, section);
            if (s.piControl != CsiSensorSettings::PiControl::Off)
                throw std::invalid_argument(
                    "section '" + section +
                    "' configures a Raspberry Pi (pi_control), which the sensor sets up at "
                    "start-up; csi-router drives an RT-AC86U");
            if (argHost.isSet()) s.ssh.host = argHost.getValue();
            if (argPort.isSet()) s.ssh.port = argPort.getValue();
            if (argUser.isSet()) s.ssh.user = argUser.getValue();
            if (argIdentity.isSet()) s.ssh.identityFile = argIdentity.getValue();
            if (argKnownHosts.isSet()) s.ssh.knownHostsFile = argKnownHosts.getValue();
            if (argAcceptNew.isSet()) s.ssh.acceptNewHostKey = true;
            if (argPasswordEnv.isSet()) s.ssh.passwordEnvVar = argPasswordEnv.getValue();

            NexmonRouterControl router(std::make_shared<SshRouterShell>(s.ssh), s.setup);
            try
            {
                const auto& command = argCommand.getValue();
                const auto& args = argArgs.getValue();
                const auto needArgs = [&](size_t n, const char* usage)
                {
                    if (args.size() != n)
                        throw std::invalid_argument(std::string("usage: csi-router ") + usage);
                };
                std::cerr << "csi-router: router " << router.shell().describe() << "\n";
                if (command == "setup")
                {
                    needArgs(0, "setup");
                    router.loadFirmwareModule();
                    std::cout << "firmware module loaded, " << s.setup.interface5G << " bridged to "
                              << s.setup.bridge << "\n";
                }
                else if (command == "configure" || command == "switch")
                {
                    if (command == "switch")
                    {
                        needArgs(1, "switch CH/BW [--measure]");
                        s.extraction.chanspec = Chanspec::fromString(args[0]);
                    }
                    else
                        needArgs(0, "configure");
                    std::unique_ptr<UdpCsiReceiver> rx;
                    if (argMeasure.isSet())
                    {
                        rx = std::make_unique<UdpCsiReceiver>(s.udp);
                        // Connect first: the downtime runs from the switch command, as in the
                        // driver, whose session is always open.
                        router.shell().run("true", s.setup.commandTimeout_s);
                    }
                    const auto start = mrpt::Clock::now();
                    router.configure(s.extraction);
                    const double commandTime =
                        std::chrono::duration<double>(mrpt::Clock::now() - start).count();
                    std::cout << "CSI on " << s.extraction.chanspec.asString() << " ("
                              << s.extraction.chanspec.asBroadcomString()
                              << " in wl notation), command round trip " << std::fixed
                              << std::setprecision(0) << commandTime * 1e3 << " ms\n";
                    if (rx)
                    {
                        const auto first = waitFirstFrame(
                            *rx, s.assembler, s.extraction.chanspec, start, argTimeout.getValue());
                        const std::string within =
                            " within " + std::to_string(argTimeout.getValue()) + " s on UDP port " +
                            std::to_string(rx->boundPort());
                        if (first.datagrams == 0)
                        {
                            std::cerr << "csi-router: error: no datagram" << within
                                      << ": the router was configured but sends no CSI here (this "
                                         "computer on the router's LAN? udp_port? a firewall?)\n";
                            return cli::kExitNoDatagrams;
                        }
                        if (!first.downtime)
                        {
                            std::string seen;
                            for (const auto& c : first.channels)
                                seen += (seen.empty() ? "" : ", ") + c;
                            std::cerr << "csi-router: error: " << first.datagrams
                                      << " datagrams but no CSI frame on "
                                      << s.extraction.chanspec.asString() << within
                                      << " (frames seen on: " << (seen.empty() ? "none" : seen)
                                      << "; no access point on that channel, or --measure-timeout "
                                         "too short)\n";
                            return cli::kExitNoMatchingFrames;
                        }
                        std::cout << "switch downtime (request -> first frame): "
                                  << *first.downtime * 1e3 << " ms\n";
                    }
                }
                else if (command == "scan")
                {
                    needArgs(0, "scan");
                    const auto aps = router.scan(s.extraction.chanspec.band);
                    std::cout << std::left << std::setw(19) << "BSSID" << std::setw(10) << "RSSI"
                              << std::setw(9) << "CHANNEL"
                              << "SSID\n";
                    for (const auto& ap : aps)
                        std::cout << std::setw(19) << ap.bssid.asString() << std::setw(10)
                                  << ap.rssi_dBm << std::setw(9) << ap.chanspec.asString() << "\""
                                  << ap.ssid << "\"\n";
                    std::cout << aps.size() << " access points\n";
                }
                else if (command == "status")
                {
                    needArgs(0, "status");
                    const auto cs = router.currentChanspec(s.extraction.chanspec.band);
                    std::cout << "chanspec 0x" << std::hex << cs.raw << std::dec << ": channel "
                              << cs.asString() << " (" << cs.asBroadcomString()
                              << " in wl notation)\n";
                }
                else if (command == "transmit")
                {
                    needArgs(1, "transmit start|stop");
                    if (args[0] == "start")
                        router.startTransmitter(s.transmitter, s.extraction.chanspec.band);
                    else if (args[0] == "stop")
                        router.stopTransmitter();
                    else
                        throw std::invalid_argument("usage: csi-router transmit start|stop");
                    std::cout << "transmitter " << args[0] << "ed\n";
                }
                else
                    throw std::invalid_argument("unknown command '" + command + "' (see --help)");
            }
            catch (const RouterError& e)
            {
                // The transport or a router command failed: its own status, so scripts can
                // tell "router not reachable / refused" from a bad command line.
                std::cerr << "csi-router: error: " << cli::exceptionMessage(e) << "\n";
                return cli::kExitRouterControlFailed;
            }
            return 0;
        });
}
