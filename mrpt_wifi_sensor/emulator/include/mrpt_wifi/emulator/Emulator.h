/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPose2D.h>
#include <mrpt/math/TTwist2D.h>
#include <mrpt_wifi/emulator/ControlSocket.h>
#include <mrpt_wifi/emulator/FaultInjector.h>
#include <mrpt_wifi/emulator/LoopbackUdp.h>
#include <mrpt_wifi/emulator/RouterModel.h>
#include <mrpt_wifi/emulator/SerialPty.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/sensor/PcapIO.h>
#include <mrpt_wifi/sim/Scenario.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace mrpt_wifi::emulator
{
/** The device the emulator plays. */
enum class EmulatedDevice : uint8_t
{
    RtAc86u = 0,  //!< BCM4366c0 packed-float datagrams over UDP, router tools (wl, nexutil, ...)
    RaspberryPi,  //!< BCM43455c0 int16 datagrams (one core) over UDP, Pi tools (nexutil, ip, iw)
    Esp32         //!< esp-csi CSI_DATA lines on a pseudo-terminal (serial port), 20 MHz L-LTF
};
const char* toString(EmulatedDevice d);
/** Parses "rt-ac86u|raspberry-pi|esp32"; throws std::invalid_argument otherwise. */
EmulatedDevice emulatedDeviceFromString(const std::string& s);

/** Everything the emulator needs; rt-ac86u-emulator fills it from its command line. */
struct EmulatorOptions
{
    EmulatedDevice device = EmulatedDevice::RtAc86u;
    /** Esp32: a symbolic link to the pseudo-terminal's slave, for a fixed path in a .ini
     * (empty: only the /dev/pts/N name, printed and in the status JSON). */
    std::string serialLink;
    /** Everything actually sent, for comparison with what a receiver decoded: a pcap of the
     * datagrams (UDP devices) or the CSI_DATA lines completely written (Esp32). Empty: none. */
    std::string recordSentFile;

    /** @name Source: exactly one of a scenario (file or in code) or a capture to replay.
     * @{ */
    std::string scenarioFile;
    std::optional<sim::Scenario> scenario;
    std::string replayFile;
    uint16_t replayUdpPort = 5500;  //!< destination port of the datagrams in the capture (0: any)
    /** @} */

    std::string destinationHost = "127.0.0.1";  //!< loopback only (127.0.0.0/8, ::1)
    uint16_t port = 5500;
    /** Scenario mode: also stream the robot's (noisy, drifting) wheel odometry of the scenario
     * as it happens, one text datagram per sample to destinationHost:odometryPort, for
     * CWiFiOdometryUdpSensor (format: odometryDatagram()). 0: off. */
    uint16_t odometryPort = 0;

    /** Where emulator.sock and bin/ (links to the shim) go; empty: no control socket. */
    std::string stateDir;
    /** Program the bin/ links point to (rt-ac86u-shim); empty: no links. */
    std::string shimPath;

    NexmonHeaderVariant format = NexmonHeaderVariant::Nexmon;
    /** Replay: re-encode datagrams in `format` instead of sending them as recorded. */
    bool convertReplayFormat = false;
    double speed = 1.0;                   //!< simulated seconds per wall-clock second
    double duration_s = 3600.0;           //!< wall-clock bound of run()
    uint64_t maxDatagrams = 100'000'000;  //!< bound on datagrams put on the wire
    /** Seed of the fault injection (loss, duplication, reordering, corruption, silences) only;
     * the simulated world has its own seed, scenarioSeed. */
    uint64_t faultSeed = 1;
    /** Seed of the simulated world (impairments such as the receiver's phase offsets, the
     * multipath, the drive's noise): replaces the scenario's `seed:` key, as wifi-sim --seed
     * does. Unset: the scenario's own. */
    std::optional<uint32_t> scenarioSeed;
    /** Scenario mode: folder for the ground truth written live, on the receiver's clock
     * (trajectory_tum.txt: unix time at which the robot was at each pose, the clock the CSI
     * and odometry datagrams are timestamped with on arrival; transmitters.yaml). Empty: none. */
    std::string truthDir;
    FaultSettings faults;
    RouterTiming timing;
    /** Start with the CSI module loaded and CSI configured on this channel (no setup needed). */
    std::optional<Chanspec> preconfigured;
    bool loop = false;  //!< restart the scenario / capture at its end instead of stopping
    /** First byte of the simulated 802.11 frames (frame control; 0x88 = QoS data), matched by
     * makecsiparams -b. */
    uint8_t frameTypeByte = 0x88;
    std::vector<double> rebootAt_s;  //!< scheduled reboots [s since start, wall clock]

    double statusPeriod_s = 0;             //!< a status line every so often (0: none)
    std::ostream* statusStream = nullptr;  //!< status lines and the command log (null: silent)
    bool logCommands = false;
};

/** Counters of the data plane (everything before the fault injector). */
struct DataPlaneCounters
{
    uint64_t framesHeard = 0;  //!< frames of transmitters on a channel the router captures
    uint64_t framesDroppedMacFilter = 0;
    uint64_t framesDroppedPacketFilter = 0;
    uint64_t framesDroppedBusy = 0;     //!< within the CSI engine's delay after the previous one
    uint64_t framesDroppedMasks = 0;    //!< no (core, stream) pair left after the masks
    uint64_t framesDroppedSilence = 0;  //!< a silence episode started on this frame
    uint64_t framesEmitted = 0;
    uint64_t pairsMasked = 0;         //!< (core, stream) pairs removed by the masks
    uint64_t datagramsGenerated = 0;  //!< encoded, before faults
    uint64_t datagramsOverLimit = 0;  //!< not sent because maxDatagrams was reached
    uint64_t replayRead = 0;
    uint64_t replayUnparsable = 0;
    uint64_t replayOffChannel = 0;  //!< not on a captured channel (or CSI silent)
    uint64_t reboots = 0;
    uint64_t rewinds = 0;       //!< simulator restarts after channel / state changes
    uint64_t odometrySent = 0;  //!< odometry datagrams (odometryPort)
    double maxLag_s = 0;        //!< worst lateness of a send vs. its real-time schedule
    /** Scenario frames emitted per transmitter (MAC as text): what each AP sent the receiver,
     *  to compare with what it got. */
    std::map<std::string, uint64_t> framesEmittedByTransmitter;
};

enum class StopReason : uint8_t
{
    Running = 0,
    Requested,  //!< requestStop(), emulator-ctl stop, SIGINT/SIGTERM
    Duration,
    MaxDatagrams,
    EndOfSource
};
const char* toString(StopReason r);

/** The odometry datagram: one ASCII line
 *  `MRPT_WIFI_ODO 1 SEQ SIM_TIME_S X Y PHI VX VY OMEGA\n` — sequence number, simulated time [s],
 *  the accumulated odometry pose (odometry frame; m, m, rad) and the measured body-frame
 *  velocity (m/s, m/s, rad/s). Receivers timestamp it on arrival, as they do the CSI. */
std::string odometryDatagram(
    uint64_t seq, double simTime_s, const mrpt::math::TPose2D& odometry,
    const mrpt::math::TTwist2D& velocityLocal);

/** The emulated RT-AC86U: a RouterModel driven through a Unix socket by the command shims,
 * and a data plane that sends the CSI the router would report as Nexmon datagrams over UDP to
 * a loopback address, paced in real time × speed, through a FaultInjector.
 *
 * Scenario mode: the Simulator only synthesises frames of transmitters on the channels the
 * router is tuned to and capturing (setChannelFilter + rewind on every change), so a silent
 * router costs nothing. Replay mode: datagrams of a capture, filtered the same way.
 *
 * Single-threaded: run() serves the socket between sends. requestStop() may be called from a
 * signal handler or another thread; everything else from run()'s thread (or when not running).
 */
class Emulator
{
public:
    /** Validates everything (loopback destination, readable source, state directory) and
     * throws std::invalid_argument / std::runtime_error / sim::ScenarioError with a clear
     * message; nothing is sent before run(). */
    explicit Emulator(EmulatorOptions options);
    ~Emulator();
    Emulator(const Emulator&) = delete;
    Emulator& operator=(const Emulator&) = delete;

    /** Serves until a stop condition; the pending reordered datagram is flushed. */
    StopReason run();
    /** Async-signal-safe. */
    void requestStop();

    /** Runs one router command or emulator-ctl verb (what the socket does). */
    ToolResult handleCommand(const Argv& argv);
    /** Status and counters as JSON (share/emulator/README.md lists the fields). */
    std::string statusJson() const;
    /** One human-readable line. */
    std::string statusLine() const;

    const RouterModel& router() const { return router_; }
    const DataPlaneCounters& counters() const { return counters_; }
    const FaultCounters& faultCounters() const { return faults_.counters(); }
    uint64_t datagramsSent() const { return sender_->datagramsSent(); }
    const LoopbackDestination& destination() const { return sender_->destination(); }
    /** Esp32: the path a reader opens (the link, else /dev/pts/N); empty for other devices. */
    std::string serialDevice() const { return serial_ ? serial_->devicePath() : std::string(); }
    /** Datagrams sent (UDP devices) or CSI lines queued (Esp32): what maxDatagrams bounds. */
    uint64_t itemsSent() const;
    std::string socketPath() const;
    std::string binDir() const;
    StopReason stopReason() const { return stopReason_; }
    /** The scenario being emulated (null in replay mode). */
    const sim::Scenario* scenario() const;

    /** Seconds since construction (the router's clock). */
    double uptime_s() const;
    /** Current simulated time (scenario) or capture time (replay). */
    double simTime_s() const;

private:
    struct Source;
    struct ReplaySource;
    struct ScenarioSource;

    ToolResult control(const Argv& args);
    void reboot();
    void refreshCaptures(double now);
    void processDue(double now);
    void sendDueOdometry(double now);
    void writeDueTruth(double now);
    void openTruth();
    void processScenarioFrame(CObservationWiFiCSI& obs, double t);
    void processReplayDatagram(std::vector<uint8_t>& d, double t);
    void emit(std::vector<uint8_t>&& datagram, double t);
    const ActiveCapture* captureFor(const Chanspec& cs) const;
    double nextWakeup(double now);
    void reanchor(double now);
    double simAt(double now) const;
    double wallAt(double simTime) const;
    std::vector<ScanEntry> scan(WifiBand band);

    EmulatorOptions opt_;
    std::chrono::steady_clock::time_point origin_;
    double unixOrigin_ = 0;  //!< UNIX time of origin_ (to line recordings up with the truth)
    RouterModel router_;
    FaultInjector faults_;
    std::unique_ptr<LoopbackUdpSender> sender_;
    std::unique_ptr<LoopbackUdpSender> odometrySender_;  //!< odometryPort != 0
    size_t nextOdometry_ = 0;
    std::unique_ptr<std::ofstream> truthTrajectory_;  //!< truthDir/trajectory_tum.txt
    size_t nextTruthSample_ = 0;                      //!< next sample (× truthStep_) to write
    double truthStep_ = 0.01;                         //!< simulated seconds between samples
    double lastTruthFlush_ = 0;
    std::unique_ptr<ControlServer> control_;
    std::unique_ptr<PtySerialPort> serial_;  //!< Esp32
    uint64_t serialLinesQueued_ = 0;
    std::unique_ptr<PcapWriter> sentPcap_;      //!< recordSentFile, UDP devices
    std::unique_ptr<std::ofstream> sentLines_;  //!< recordSentFile, Esp32
    void flushSerial();
    std::unique_ptr<Source> source_;
    DataPlaneCounters counters_;

    // Clock: sim = simAnchor_ + (wall - wallAnchor_) · speed, frozen while paused.
    double wallAnchor_ = 0, simAnchor_ = 0;
    double speed_ = 1.0;
    bool paused_ = false;
    double silencedUntil_ = -1;
    double lastItemTime_ = 0;  // stream time of the previous item (silence draws)

    std::vector<ActiveCapture> captures_;
    std::string captureSignature_;                  // what the source was last configured for
    std::map<std::string, double> lastCsiTime_;     // per interface: the CSI engine's busy model
    std::map<MacAddress, ScanEntry> seenInReplay_;  // replay: what `wl scan` reports
    uint16_t firmwareCounter_ = 0;
    size_t nextScheduledReboot_ = 0;

    std::atomic<bool> stopRequested_{false};
    int wakePipe_[2] = {-1, -1};
    StopReason stopReason_ = StopReason::Running;
    double lastStatusLine_ = 0;
};

}  // namespace mrpt_wifi::emulator
