/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * rt-ac86u-emulator: an Asus RT-AC86U with Nexmon CSI firmware on loopback. Sends the CSI
 * datagrams the router would send, from a simulated scenario or a capture, to 127.0.0.1:PORT,
 * and obeys the router's own command-line tools (run through STATE_DIR/bin/, e.g. by an sshd). */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt_wifi/emulator/Emulator.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>

using namespace mrpt_wifi;
using namespace mrpt_wifi::emulator;

namespace
{
Emulator* g_emulator = nullptr;

void onSignal(int)
{
    if (g_emulator) g_emulator->requestStop();
}

std::string defaultStateDir(unsigned port)
{
    const char* runtime = std::getenv("XDG_RUNTIME_DIR");
    const std::string base = runtime && *runtime ? runtime : "/tmp";
    return base + "/rt-ac86u-emulator." + std::to_string(port);
}

std::string defaultShim()
{
    std::error_code ec;
    const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
    return ec ? std::string("rt-ac86u-shim") : (self.parent_path() / "rt-ac86u-shim").string();
}

std::vector<double> parseTimes(const std::string& text)
{
    std::vector<double> out;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ','))
    {
        if (item.empty()) continue;
        size_t used = 0;
        double v = -1;
        try
        {
            v = std::stod(item, &used);
        }
        catch (const std::exception&)
        {
            used = 0;
        }
        if (used != item.size() || !(v >= 0))
            throw std::invalid_argument("--reboot-at: '" + item + "' is not a time in seconds");
        out.push_back(v);
    }
    return out;
}

NexmonHeaderVariant variantFromString(const std::string& s)
{
    switch (nexmon::formatHintFromString(s))
    {
        case nexmon::FormatHint::Nexmon:
            return NexmonHeaderVariant::Nexmon;
        case nexmon::FormatHint::NexmonLegacy:
            return NexmonHeaderVariant::NexmonLegacy;
        case nexmon::FormatHint::UbiLocate:
            return NexmonHeaderVariant::UbiLocate;
        default:
            throw std::invalid_argument("--format: give nexmon, nexmon-legacy or ubilocate");
    }
}
}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "rt-ac86u-emulator",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Emulates an Asus RT-AC86U with Nexmon CSI firmware on loopback: sends Nexmon "
                "CSI datagrams from a simulated scenario (or a replayed capture) to "
                "127.0.0.1:PORT and obeys the router tools wl, nexutil, makecsiparams, insmod, "
                "rmmod, brctl run through STATE_DIR/bin/ (e.g. by an sshd). With --device it plays "
                "a "
                "Raspberry Pi's nexmon_csi instead (tools nexutil, makecsiparams, ip, iw) or an "
                "ESP32 writing esp-csi lines to a pseudo-terminal. Loopback only.",
                ' ', "0.1");
            TCLAP::ValueArg<std::string> argDevice(
                "", "device",
                "The device to play: rt-ac86u (BCM4366c0 datagrams, router tools), raspberry-pi "
                "(BCM43455c0 int16 datagrams, one core; tools nexutil, makecsiparams, ip, iw, "
                "ifconfig; for `source = interface:lo`) or esp32 (esp-csi CSI_DATA lines on a "
                "pseudo-terminal; for `source = serial:DEV`; needs --preconfigured CH)",
                false, "rt-ac86u", "DEVICE", cmd);
            TCLAP::ValueArg<std::string> argSerialLink(
                "", "serial-link",
                "esp32: make PATH a symbolic link to the pseudo-terminal (else its /dev/pts/N "
                "name is printed and in the status JSON)",
                false, "", "PATH", cmd);
            TCLAP::ValueArg<std::string> argRecordSent(
                "", "record-sent",
                "Write everything sent: a pcap of the datagrams, or (esp32) the CSI_DATA lines",
                false, "", "FILE", cmd);
            TCLAP::ValueArg<std::string> argScenario(
                "", "scenario", "Scenario file (YAML, share/scenarios/)", false, "", "FILE.yaml");
            TCLAP::ValueArg<std::string> argReplay(
                "", "replay", "Capture to replay instead (pcap/pcapng)", false, "", "FILE.pcap");
            cmd.xorAdd(argScenario, argReplay);
            TCLAP::ValueArg<unsigned> argReplayPort(
                "", "replay-port", "UDP port of the CSI datagrams in the capture (0: any)", false,
                5500, "PORT", cmd);
            TCLAP::ValueArg<unsigned> argPort(
                "p", "port", "Destination UDP port", false, nexmon::kDefaultUdpPort, "PORT", cmd);
            TCLAP::ValueArg<unsigned> argOdoPort(
                "", "odometry-port",
                "Also stream the scenario robot's wheel odometry, live, to this UDP port of the "
                "destination (for CWiFiOdometryUdpSensor; 0 = off)",
                false, 0, "PORT", cmd);
            TCLAP::ValueArg<std::string> argDest(
                "", "dest", "Destination address: 127.0.0.0/8, ::1 or localhost only", false,
                "127.0.0.1", "ADDR", cmd);
            TCLAP::ValueArg<std::string> argStateDir(
                "", "state-dir",
                "Folder for emulator.sock, bin/ (tool links) and summary.json "
                "[default: $XDG_RUNTIME_DIR or /tmp, /rt-ac86u-emulator.PORT]",
                false, "", "DIR", cmd);
            TCLAP::ValueArg<std::string> argShim(
                "", "shim", "The rt-ac86u-shim program the tool links point to", false,
                defaultShim(), "PATH", cmd);
            TCLAP::ValueArg<std::string> argFormat(
                "f", "format",
                "Datagram header: nexmon (current firmware), nexmon-legacy, ubilocate. Replay: "
                "re-encode in this format (default: as recorded)",
                false, "nexmon", "FORMAT", cmd);
            TCLAP::ValueArg<double> argSpeed(
                "", "speed", "Simulated seconds per wall-clock second", false, 1.0, "X", cmd);
            TCLAP::ValueArg<double> argDuration(
                "d", "duration", "Stop after this many wall-clock seconds", false, 3600.0, "S",
                cmd);
            TCLAP::ValueArg<uint64_t> argMaxDatagrams(
                "", "max-datagrams", "Stop after sending this many datagrams", false, 100000000,
                "N", cmd);
            TCLAP::ValueArg<uint32_t> argScenarioSeed(
                "", "scenario-seed",
                "Seed of the simulated world: the receiver's and the access points' phase "
                "offsets and other impairments, the per-frame noise, the drive's and the "
                "odometry's noise. Replaces the scenario file's `seed:` key (default: that key), "
                "as wifi-sim --seed does: give wifi-sim the same seed for the same world. The "
                "room and the transmitters come from the file",
                false, 1, "N", cmd);
            TCLAP::ValueArg<uint64_t> argFaultSeed(
                "", "fault-seed",
                "Seed of the fault injection only (--loss, --duplicate, --reorder, --corrupt, "
                "--silence-rate): the same world, other faults",
                false, 1, "N", cmd);
            TCLAP::ValueArg<uint64_t> argSeed(
                "", "seed", "Old name of --fault-seed (prints a note); not the scenario's seed",
                false, 1, "N", cmd);
            TCLAP::ValueArg<std::string> argTruthDir(
                "", "truth-dir",
                "Scenario: folder for the ground truth, written as the emulator runs, on the "
                "receiver's clock (trajectory_tum.txt: unix time at which the robot was at each "
                "pose, the clock of the recording or of wifi-localize's output, so scoring needs "
                "no shift; transmitters.yaml) [default: STATE_DIR/truth]",
                false, "", "DIR", cmd);
            TCLAP::ValueArg<double> argLoss(
                "", "loss", "Datagram loss probability", false, 0, "P", cmd);
            TCLAP::ValueArg<double> argDuplicate(
                "", "duplicate", "Datagram duplication probability", false, 0, "P", cmd);
            TCLAP::ValueArg<double> argReorder(
                "", "reorder", "Probability that a datagram swaps with the next", false, 0, "P",
                cmd);
            TCLAP::ValueArg<double> argCorrupt(
                "", "corrupt", "Corrupt datagram probability (truncated, bad magic, bad chanspec)",
                false, 0, "P", cmd);
            TCLAP::ValueArg<double> argSilenceRate(
                "", "silence-rate", "Silence episodes per second (Poisson)", false, 0, "HZ", cmd);
            TCLAP::ValueArg<double> argSilenceLength(
                "", "silence-length", "Length of a silence episode", false, 0.5, "S", cmd);
            TCLAP::ValueArg<std::string> argRebootAt(
                "", "reboot-at", "Reboot the router at these times (s since start)", false, "",
                "T1,T2,...", cmd);
            TCLAP::ValueArg<std::string> argPreconfigured(
                "", "preconfigured",
                "Start with the CSI module loaded and CSI on all cores/streams of this channel "
                "(no setup over ssh needed)",
                false, "", "CH/BW", cmd);
            TCLAP::ValueArg<double> argRetune(
                "", "retune-delay", "CSI silence after a channel change", false, 0.020, "S", cmd);
            TCLAP::ValueArg<double> argScanTime(
                "", "scan-time", "Duration of `wl scan` (CSI pauses meanwhile)", false, 1.0, "S",
                cmd);
            TCLAP::ValueArg<double> argRebootTime(
                "", "reboot-time", "Time the router stays unreachable after a reboot", false, 1.0,
                "S", cmd);
            TCLAP::SwitchArg argNoMonitor(
                "", "no-monitor-required", "Report CSI even without `wl monitor 1`", cmd);
            TCLAP::ValueArg<unsigned> argFrameByte(
                "", "frame-byte", "First byte of the simulated frames (makecsiparams -b)", false,
                0x88, "BYTE", cmd);
            TCLAP::SwitchArg argLoop("", "loop", "Restart the scenario/capture at its end", cmd);
            TCLAP::ValueArg<double> argStatusPeriod(
                "", "status-period", "Seconds between status lines on stderr (0: none)", false, 5.0,
                "S", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No status lines, no command log", cmd);

            if (const int rc = cli::parseCommandLine(cmd, argc, const_cast<const char**>(argv));
                rc >= 0)
                return rc;

            if (argPort.getValue() == 0 || argPort.getValue() > 65535)
                throw std::invalid_argument("--port must be in 1..65535");
            if (argOdoPort.getValue() > 65535)
                throw std::invalid_argument("--odometry-port must be in 0..65535");
            if (argFrameByte.getValue() > 255)
                throw std::invalid_argument("--frame-byte must be 0..255");
            EmulatorOptions o;
            o.device = emulatedDeviceFromString(argDevice.getValue());
            o.serialLink = argSerialLink.getValue();
            o.recordSentFile = argRecordSent.getValue();
            o.scenarioFile = argScenario.getValue();
            o.replayFile = argReplay.getValue();
            o.replayUdpPort = uint16_t(argReplayPort.getValue());
            o.destinationHost = argDest.getValue();
            o.port = uint16_t(argPort.getValue());
            o.odometryPort = uint16_t(argOdoPort.getValue());
            o.stateDir =
                argStateDir.isSet() ? argStateDir.getValue() : defaultStateDir(argPort.getValue());
            o.shimPath = argShim.getValue();
            o.format = variantFromString(argFormat.getValue());
            o.convertReplayFormat = argFormat.isSet();
            o.speed = argSpeed.getValue();
            o.duration_s = argDuration.getValue();
            o.maxDatagrams = argMaxDatagrams.getValue();
            if (argSeed.isSet() && argFaultSeed.isSet())
                throw std::invalid_argument(
                    "--seed is the old name of --fault-seed: give only --fault-seed");
            if (argSeed.isSet())
                std::cerr << "[rt-ac86u-emulator] note: --seed is the old name of --fault-seed "
                             "(it sets the fault injection's seed, not the scenario's); the "
                             "simulated world's seed is --scenario-seed (default: the scenario "
                             "file's `seed:` key)\n";
            o.faultSeed = argSeed.isSet() ? argSeed.getValue() : argFaultSeed.getValue();
            if (argScenarioSeed.isSet())
            {
                if (!argScenario.isSet())
                    throw std::invalid_argument(
                        "--scenario-seed needs --scenario (a capture replays what was "
                        "recorded)");
                o.scenarioSeed = argScenarioSeed.getValue();
            }
            if (argTruthDir.isSet() && !argScenario.isSet())
                throw std::invalid_argument(
                    "--truth-dir needs --scenario (a capture holds no robot poses)");
            if (argScenario.isSet())
                o.truthDir = argTruthDir.isSet()
                                 ? argTruthDir.getValue()
                                 : (std::filesystem::path(o.stateDir) / "truth").string();
            o.faults.loss = argLoss.getValue();
            o.faults.duplicate = argDuplicate.getValue();
            o.faults.reorder = argReorder.getValue();
            o.faults.corrupt = argCorrupt.getValue();
            o.faults.silenceRate_Hz = argSilenceRate.getValue();
            o.faults.silenceLength_s = argSilenceLength.getValue();
            o.faults.validate();
            o.rebootAt_s = parseTimes(argRebootAt.getValue());
            if (argPreconfigured.isSet())
                o.preconfigured = parseRouterChanspec(argPreconfigured.getValue());
            o.timing.retuneDelay_s = argRetune.getValue();
            o.timing.scanDuration_s = argScanTime.getValue();
            o.timing.rebootDuration_s = argRebootTime.getValue();
            o.timing.requireMonitorMode = !argNoMonitor.getValue();
            if (o.timing.retuneDelay_s < 0 || o.timing.scanDuration_s < 0 ||
                o.timing.rebootDuration_s < 0)
                throw std::invalid_argument("timings must be >= 0");
            o.frameTypeByte = uint8_t(argFrameByte.getValue());
            o.loop = argLoop.getValue();
            o.statusPeriod_s = argQuiet.getValue() ? 0.0 : argStatusPeriod.getValue();
            o.statusStream = argQuiet.getValue() ? nullptr : &std::cerr;
            o.logCommands = !argQuiet.getValue();

            Emulator emulator(o);
            g_emulator = &emulator;
            struct sigaction sa
            {
            };
            sa.sa_handler = onSignal;
            sigemptyset(&sa.sa_mask);
            sigaction(SIGINT, &sa, nullptr);
            sigaction(SIGTERM, &sa, nullptr);

            if (!emulator.serialDevice().empty())  // wherever the output goes: scripts need it
                std::cerr << "[rt-ac86u-emulator] ESP32 serial port: " << emulator.serialDevice()
                          << std::endl;
            if (!argQuiet.getValue())
            {
                std::cerr << "[rt-ac86u-emulator] device " << toString(o.device);
                if (o.device == EmulatedDevice::Esp32)
                    std::cerr << ": CSI_DATA lines on " << emulator.serialDevice() << "\n";
                else
                    std::cerr << ": sending to " << emulator.destination().asString() << " ("
                              << toString(o.format) << ")\n";
                std::cerr << "[rt-ac86u-emulator] "
                          << (o.device == EmulatedDevice::RaspberryPi
                                  ? "Pi tools: " + emulator.binDir() +
                                        "/{nexutil,makecsiparams,ip,iw,ifconfig,emulator-ctl}"
                                  : "router tools: " + emulator.binDir() +
                                        "/{wl,nexutil,makecsiparams,insmod,rmmod,brctl,"
                                        "emulator-ctl}")
                          << "\n[rt-ac86u-emulator] socket: " << emulator.socketPath() << "\n";
                if (!o.truthDir.empty())
                    std::cerr << "[rt-ac86u-emulator] ground truth on the receiver's clock: "
                              << o.truthDir << "/trajectory_tum.txt (scenario seed "
                              << emulator.scenario()->seed << ", fault seed " << o.faultSeed
                              << ")\n";
                if (o.device == EmulatedDevice::RaspberryPi && !o.preconfigured)
                    std::cerr << "[rt-ac86u-emulator] CSI is off until the Pi is set up "
                                 "(ip link set wlan0 up; nexutil -Iwlan0 -s500 -b -l34 -v...; iw "
                                 "dev wlan0 interface add mon0 type monitor; ip link set mon0 "
                                 "up), or use --preconfigured CH/BW\n";
                else if (o.device == EmulatedDevice::RtAc86u && !o.preconfigured)
                    std::cerr << "[rt-ac86u-emulator] CSI is off until the router is set up "
                                 "(rmmod dhd; insmod dhd.ko; brctl addif br0 eth6; wl ...; "
                                 "nexutil ...), or use --preconfigured CH/BW\n";
            }
            const StopReason why = emulator.run();
            g_emulator = nullptr;
            if (!argQuiet.getValue())
                std::cerr << emulator.statusLine()
                          << "\n[rt-ac86u-emulator] stopped: " << toString(why) << "\n";
            std::cout << emulator.statusJson() << std::endl;
            return 0;
        });
}
