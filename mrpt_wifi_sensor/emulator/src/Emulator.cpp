/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <fcntl.h>
#include <mrpt/core/Clock.h>
#include <mrpt/core/format.h>
#include <mrpt_wifi/emulator/Emulator.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>
#include <mrpt_wifi/sensor/PcapIO.h>
#include <mrpt_wifi/sim/GroundTruthWriter.h>
#include <mrpt_wifi/sim/Simulator.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

#include "Json.h"

namespace mrpt_wifi::emulator
{
namespace fs = std::filesystem;
using detail::JsonObject;
using detail::jsonQuote;

namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMaxPollWait_s = 0.2;   // keeps the loop's bounds (duration, stop) responsive
constexpr int kItemsPerIteration = 512;  // then serve the socket even when far behind
constexpr int kMinScanRssi_dBm = -95;    // below this a scan doesn't see the AP

bool sameChannel(const Chanspec& a, const Chanspec& b)
{
    return a.centerChannel == b.centerChannel && a.bandwidthMHz == b.bandwidthMHz &&
           a.band == b.band;
}

std::string baseName(const std::string& p)
{
    const auto slash = p.find_last_of('/');
    return slash == std::string::npos ? p : p.substr(slash + 1);
}
}  // namespace

const char* toString(StopReason r)
{
    switch (r)
    {
        case StopReason::Running:
            return "running";
        case StopReason::Requested:
            return "stop requested";
        case StopReason::Duration:
            return "duration reached";
        case StopReason::MaxDatagrams:
            return "max datagrams reached";
        case StopReason::EndOfSource:
            return "end of scenario/capture";
    }
    return "?";
}

const char* toString(EmulatedDevice d)
{
    switch (d)
    {
        case EmulatedDevice::RtAc86u:
            return "rt-ac86u";
        case EmulatedDevice::RaspberryPi:
            return "raspberry-pi";
        case EmulatedDevice::Esp32:
            return "esp32";
    }
    return "?";
}

EmulatedDevice emulatedDeviceFromString(const std::string& s)
{
    for (auto d : {EmulatedDevice::RtAc86u, EmulatedDevice::RaspberryPi, EmulatedDevice::Esp32})
        if (s == toString(d)) return d;
    throw std::invalid_argument("device '" + s + "' (give rt-ac86u, raspberry-pi or esp32)");
}

std::string odometryDatagram(
    uint64_t seq, double simTime_s, const mrpt::math::TPose2D& odometry,
    const mrpt::math::TTwist2D& velocityLocal)
{
    return mrpt::format(
        "MRPT_WIFI_ODO 1 %llu %.6f %.6f %.6f %.8f %.6f %.6f %.8f\n",
        static_cast<unsigned long long>(seq), simTime_s, odometry.x, odometry.y, odometry.phi,
        velocityLocal.vx, velocityLocal.vy, velocityLocal.omega);
}

// ------------------------------------------------------------------------------------ sources
struct Emulator::Source
{
    virtual ~Source() = default;
    /** The router now captures `captures` (empty: nothing) from stream time `t`. */
    virtual void configure(const std::vector<ActiveCapture>& captures, double t) = 0;
    /** Stream time of the next item, false if there is none for now. */
    virtual bool peek(double& t) = 0;
    /** Hands the peeked item to the emulator and moves on. */
    virtual void consume(Emulator& e) = 0;
    virtual bool ended(double streamTime) const = 0;
    virtual void restart() = 0;
    virtual std::string kind() const = 0;
};

struct Emulator::ScenarioSource : Emulator::Source
{
    explicit ScenarioSource(sim::Scenario sc) : sim(std::move(sc))
    {
        sim.setOdometryEnabled(false);
    }

    void configure(const std::vector<ActiveCapture>& captures, double t) override
    {
        have = false;
        exhausted = false;
        active = !captures.empty();
        if (!active) return;
        // One channel: let the simulator skip the others; several (eth5 + eth6): filter later.
        bool oneChannel = true;
        for (const auto& c : captures)
            oneChannel = oneChannel && sameChannel(c.chanspec, captures.front().chanspec);
        sim.setChannelFilter(
            oneChannel ? std::optional<Chanspec>(captures.front().chanspec) : std::nullopt);
        sim.rewind(std::max(0.0, t));
    }
    bool peek(double& t) override
    {
        if (!active) return false;
        while (!have)
        {
            if (exhausted || !sim.next(event))
            {
                exhausted = true;
                return false;
            }
            have = event.kind == sim::SimEvent::Kind::Csi;
        }
        t = event.time_s;
        return true;
    }
    void consume(Emulator& e) override
    {
        have = false;
        e.processScenarioFrame(*event.csi, event.time_s);
    }
    bool ended(double streamTime) const override { return streamTime >= sim.duration(); }
    void restart() override
    {
        sim.rewind(0);
        have = false;
        exhausted = false;
    }
    std::string kind() const override { return "scenario"; }

    sim::Simulator sim;
    sim::SimEvent event;
    bool have = false, active = false, exhausted = false;
    CObservationWiFiCSI scratch;  // scan results
    sim::FrameTruth scratchTruth;
};

struct Emulator::ReplaySource : Emulator::Source
{
    ReplaySource(std::string file, uint16_t udpPort) : path(std::move(file)), port(udpPort)
    {
        restart();
    }
    void configure(const std::vector<ActiveCapture>&, double) override {}
    bool peek(double& t) override
    {
        if (!have && !eof)
        {
            PcapUdpDatagram d;
            if (reader->next(d))
            {
                payload.assign(d.payload, d.payload + d.payloadLength);
                const double ts = mrpt::Clock::toDouble(d.timestamp);
                if (std::isnan(firstTimestamp)) firstTimestamp = ts;
                time = ts - firstTimestamp;
                have = true;
            }
            else
                eof = true;
        }
        t = time;
        return have;
    }
    void consume(Emulator& e) override
    {
        have = false;
        e.processReplayDatagram(payload, time);
    }
    bool ended(double) const override { return eof && !have; }
    void restart() override
    {
        reader = std::make_unique<PcapReader>(path, port);
        firstTimestamp = std::numeric_limits<double>::quiet_NaN();
        have = eof = false;
    }
    std::string kind() const override { return "replay"; }

    std::string path;
    uint16_t port;
    std::unique_ptr<PcapReader> reader;
    std::vector<uint8_t> payload;
    double firstTimestamp = 0, time = 0;
    bool have = false, eof = false;
};

// -------------------------------------------------------------------------------- construction
Emulator::Emulator(EmulatorOptions options)
    : opt_(std::move(options)),
      origin_(std::chrono::steady_clock::now()),
      unixOrigin_(mrpt::Clock::toDouble(mrpt::Clock::now())),
      router_(
          opt_.timing, opt_.device == EmulatedDevice::RaspberryPi ? RouterKind::RaspberryPi
                                                                  : RouterKind::RtAc86u),
      faults_(opt_.faultSeed, opt_.faults)
{
    const int sources = int(!opt_.scenarioFile.empty()) + int(opt_.scenario.has_value()) +
                        int(!opt_.replayFile.empty());
    if (sources != 1)
        throw std::invalid_argument("give exactly one source: a scenario or a capture to replay");
    if (!(opt_.speed > 0 && opt_.speed <= 1e6))
        throw std::invalid_argument("speed must be in (0, 1e6]");
    if (!(opt_.duration_s > 0)) throw std::invalid_argument("duration must be > 0 s");
    if (opt_.maxDatagrams == 0) throw std::invalid_argument("max datagrams must be > 0");
    speed_ = opt_.speed;
    if (opt_.device == EmulatedDevice::RaspberryPi && opt_.format == NexmonHeaderVariant::UbiLocate)
        throw std::invalid_argument("a Raspberry Pi sends nexmon or nexmon-legacy datagrams");
    if (opt_.device == EmulatedDevice::Esp32)
    {
        if (!opt_.replayFile.empty())
            throw std::invalid_argument("the ESP32 plays a scenario, not a Nexmon capture");
        if (!opt_.preconfigured || opt_.preconfigured->bandwidthMHz != 20)
            throw std::invalid_argument(
                "the ESP32 needs the channel it listens on: --preconfigured CH (20 MHz)");
    }
    else if (!opt_.serialLink.empty())
        throw std::invalid_argument("a serial link is for --device esp32");

    // Loopback check first: nothing else matters if the destination is not allowed.
    sender_ =
        std::make_unique<LoopbackUdpSender>(loopbackDestination(opt_.destinationHost, opt_.port));
    if (opt_.odometryPort != 0)
    {
        if (!opt_.replayFile.empty())
            throw std::invalid_argument(
                "the odometry stream needs a scenario (a capture holds no odometry)");
        if (opt_.odometryPort == opt_.port)
            throw std::invalid_argument("the odometry port must differ from the CSI port");
        odometrySender_ = std::make_unique<LoopbackUdpSender>(
            loopbackDestination(opt_.destinationHost, opt_.odometryPort));
    }

    if (!opt_.replayFile.empty())
    {
        if (opt_.scenarioSeed)
            throw std::invalid_argument(
                "a scenario seed needs a scenario (a capture replays what was recorded)");
        if (!opt_.truthDir.empty())
            throw std::invalid_argument(
                "the ground truth needs a scenario (a capture holds no robot poses)");
        source_ = std::make_unique<ReplaySource>(opt_.replayFile, opt_.replayUdpPort);
    }
    else
    {
        sim::Scenario sc =
            opt_.scenario ? *opt_.scenario : sim::Scenario::fromYamlFile(opt_.scenarioFile);
        if (opt_.scenarioSeed) sc.seed = *opt_.scenarioSeed;
        source_ = std::make_unique<ScenarioSource>(std::move(sc));
        if (!opt_.truthDir.empty()) openTruth();
    }

    if (opt_.device == EmulatedDevice::Esp32)
        serial_ = std::make_unique<PtySerialPort>(opt_.serialLink);
    if (!opt_.recordSentFile.empty())
    {
        if (serial_)
        {
            sentLines_ = std::make_unique<std::ofstream>(opt_.recordSentFile);
            if (!*sentLines_)
                throw std::runtime_error("cannot create '" + opt_.recordSentFile + "'");
        }
        else
            sentPcap_ = std::make_unique<PcapWriter>(opt_.recordSentFile);
    }

    router_.setScanProvider([this](WifiBand band) { return scan(band); });
    if (opt_.preconfigured) router_.preconfigure(*opt_.preconfigured, 0.0);
    std::sort(opt_.rebootAt_s.begin(), opt_.rebootAt_s.end());

    if (::pipe2(wakePipe_, O_NONBLOCK | O_CLOEXEC) != 0)
        throw std::runtime_error("cannot create the wake-up pipe");

    if (!opt_.stateDir.empty())
    {
        const fs::path bin = fs::path(opt_.stateDir) / "bin";
        fs::create_directories(bin);
        if (!opt_.shimPath.empty())
        {
            const fs::path shim = fs::absolute(opt_.shimPath);
            if (!fs::exists(shim))
                throw std::runtime_error("command shim '" + shim.string() + "' not found");
            for (const auto& name : shimToolNames())
            {
                const fs::path link = bin / name;
                std::error_code ec;
                fs::remove(link, ec);
                fs::create_symlink(shim, link);
            }
        }
        control_ = std::make_unique<ControlServer>(
            (fs::path(opt_.stateDir) / kSocketFileName).string(),
            [this](const Argv& argv) { return handleCommand(argv); });
    }
}

Emulator::~Emulator()
{
    for (int fd : wakePipe_)
        if (fd >= 0) ::close(fd);
}

std::string Emulator::socketPath() const
{
    return control_ ? control_->path() : std::string();
}

std::string Emulator::binDir() const
{
    return opt_.stateDir.empty() ? std::string() : (fs::path(opt_.stateDir) / "bin").string();
}

const sim::Scenario* Emulator::scenario() const
{
    const auto* s = dynamic_cast<const ScenarioSource*>(source_.get());
    return s ? &s->sim.scenario() : nullptr;
}

double Emulator::uptime_s() const
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - origin_).count();
}

double Emulator::simAt(double now) const
{
    return paused_ ? simAnchor_ : simAnchor_ + (now - wallAnchor_) * speed_;
}

double Emulator::wallAt(double simTime) const
{
    return paused_ ? kInf : wallAnchor_ + (simTime - simAnchor_) / speed_;
}

double Emulator::simTime_s() const
{
    return simAt(uptime_s());
}

void Emulator::reanchor(double now)
{
    simAnchor_ = simAt(now);
    wallAnchor_ = now;
}

void Emulator::requestStop()
{
    stopRequested_ = true;
    if (wakePipe_[1] >= 0)
    {
        const char byte = 1;
        [[maybe_unused]] const ssize_t n = ::write(wakePipe_[1], &byte, 1);
    }
}

// -------------------------------------------------------------------------------- data plane
const ActiveCapture* Emulator::captureFor(const Chanspec& cs) const
{
    for (const auto& c : captures_)
        if (sameChannel(c.chanspec, cs)) return &c;
    return nullptr;
}

void Emulator::refreshCaptures(double now)
{
    const bool silent = paused_ || now < silencedUntil_;
    captures_ = silent ? std::vector<ActiveCapture>{} : router_.activeCaptures(now);
    std::string signature;
    for (const auto& c : captures_)
        signature += c.interfaceName + ":" + std::to_string(c.chanspec.raw) + ";";
    if (signature == captureSignature_) return;
    captureSignature_ = signature;
    // Whatever was held back for reordering leaves before the gap, as a real link would.
    faults_.flush([this](const std::vector<uint8_t>& d) { emit(std::vector<uint8_t>(d), -1); });
    source_->configure(captures_, simAt(now));
    if (!captures_.empty() && dynamic_cast<ScenarioSource*>(source_.get())) ++counters_.rewinds;
}

uint64_t Emulator::itemsSent() const
{
    return serial_ ? serialLinesQueued_ : sender_->datagramsSent();
}

void Emulator::flushSerial()
{
    if (!serial_) return;
    serial_->flush(
        [this](const std::string& line)
        {
            if (sentLines_) *sentLines_ << line << std::flush;
        });
}

void Emulator::emit(std::vector<uint8_t>&& datagram, double t)
{
    auto sink = [this](const std::vector<uint8_t>& d)
    {
        if (sender_->datagramsSent() >= opt_.maxDatagrams)
        {
            ++counters_.datagramsOverLimit;
            return;
        }
        if (sender_->send(d.data(), d.size()) && sentPcap_)
            sentPcap_->writeUdp(
                d.data(), d.size(), mrpt::Clock::now(), 0x7F000001, 0x7F000001, opt_.port);
    };
    if (t < 0)
        sink(datagram);  // a released datagram: already through the faults
    else
        faults_.submit(std::move(datagram), t, sink);
}

void Emulator::processScenarioFrame(CObservationWiFiCSI& obs, double t)
{
    const ActiveCapture* cap = captureFor(obs.chanspec);
    if (!cap) return;  // several channels captured and this frame is on none of them
    ++counters_.framesHeard;
    const double dtWall = std::max(0.0, t - lastItemTime_) / speed_;
    lastItemTime_ = t;
    if (faults_.silenceStarts(dtWall))
    {
        ++counters_.framesDroppedSilence;
        silencedUntil_ = uptime_s() + faults_.settings().silenceLength_s;
        return;  // the next refreshCaptures() puts the source to sleep
    }
    const CsiParams& p = cap->csi;
    if (!p.hardwareMacFilterPasses(obs.transmitter))
    {
        ++counters_.framesDroppedMacFilter;
        return;
    }
    if (p.usePacketFilter && p.firstPacketByte != opt_.frameTypeByte)
    {
        ++counters_.framesDroppedPacketFilter;
        return;
    }
    if (p.delay_us)
    {
        // The CSI engine is busy for `delay` µs after each report; frames meanwhile are missed.
        auto it = lastCsiTime_.find(cap->interfaceName);
        if (it != lastCsiTime_.end() && t >= it->second && t - it->second < p.delay_us * 1e-6)
        {
            ++counters_.framesDroppedBusy;
            return;
        }
        lastCsiTime_[cap->interfaceName] = t;
    }
    // The Pi's 43455c0 and the ESP32 have one antenna and report one stream.
    const bool singleChain = opt_.device != EmulatedDevice::RtAc86u;
    uint8_t coresSent = 0, streamsSent = 0;
    for (unsigned tx = 0; tx < obs.nTx; ++tx)
        for (unsigned rx = 0; rx < obs.nRx; ++rx)
        {
            if (!obs.isPresent(tx, rx)) continue;
            const bool wanted = rx < nexmon::kMaxCores && tx < nexmon::kMaxStreams &&
                                ((p.coreMask >> rx) & 1) && ((p.nssMask >> tx) & 1) &&
                                (!singleChain || (rx == 0 && tx == 0));
            if (!wanted)
            {
                obs.setPresent(tx, rx, false);
                ++counters_.pairsMasked;
                continue;
            }
            coresSent |= uint8_t(1u << rx);
            streamsSent |= uint8_t(1u << tx);
        }
    if (!obs.presentPairs())
    {
        ++counters_.framesDroppedMasks;
        return;
    }
    if (opt_.device == EmulatedDevice::Esp32)
    {
        ++counters_.framesEmitted;
        ++counters_.framesEmittedByTransmitter[obs.transmitter.asString()];
        if (serialLinesQueued_ >= opt_.maxDatagrams)
        {
            ++counters_.datagramsOverLimit;
            return;
        }
        const auto us = uint64_t(std::max(0.0, t) * 1e6);
        if (serial_->submit(esp32CsiLine(obs, uint32_t(counters_.framesEmitted), us)))
            ++serialLinesQueued_;
        ++counters_.datagramsGenerated;
        flushSerial();
        return;
    }
    if (opt_.device == EmulatedDevice::RaspberryPi)
    {
        // int16 words: scale so the largest component is 2^11, as the chip's AGC keeps it.
        auto* h = obs.pair(0, 0);
        float maxAbs = 0;
        for (unsigned i = 0; i < obs.nfft(); ++i)
            maxAbs = std::max({maxAbs, std::abs(h[i].real()), std::abs(h[i].imag())});
        if (maxAbs > 0)
            for (unsigned i = 0; i < obs.nfft(); ++i) h[i] *= 2048.0f / maxAbs;
    }
    obs.headerVariant = opt_.format;
    // The firmware reports the radio's chanspec word (same channel; its sideband may differ
    // from the scenario's, e.g. 157/80 = 0xe29b vs 155/80 = 0xe09b).
    obs.chanspec = cap->chanspec;
    if (opt_.format == NexmonHeaderVariant::UbiLocate) obs.firmwareCounter = firmwareCounter_++;
    auto datagrams = nexmon::encodeFrame(
        obs, opt_.device == EmulatedDevice::RaspberryPi ? nexmon::Chip::BCM43455c0
                                                        : nexmon::Chip::BCM4366c0);
    ++counters_.framesEmitted;
    ++counters_.framesEmittedByTransmitter[obs.transmitter.asString()];
    for (auto& d : datagrams)
    {
        if (opt_.format == NexmonHeaderVariant::UbiLocate)
        {
            // headerFor() announces every chain of the frame; the firmware announces what it
            // was told to report.
            d[2] = coresSent;
            d[3] = streamsSent;
        }
        ++counters_.datagramsGenerated;
        emit(std::move(d), t);
    }
}

void Emulator::processReplayDatagram(std::vector<uint8_t>& d, double t)
{
    ++counters_.replayRead;
    nexmon::DatagramHeader h;
    nexmon::RejectReason why;
    if (!nexmon::parseHeader(d.data(), d.size(), nexmon::FormatHint::Auto, h, why))
    {
        ++counters_.replayUnparsable;
        return;
    }
    ScanEntry& seen = seenInReplay_[h.transmitter];
    seen.bssid = h.transmitter;
    seen.chanspec = h.chanspec;
    if (h.variant == NexmonHeaderVariant::Nexmon) seen.rssi_dBm = h.rssi_dBm;

    const ActiveCapture* cap = captureFor(h.chanspec);
    if (!cap)
    {
        ++counters_.replayOffChannel;
        return;
    }
    ++counters_.framesHeard;  // per datagram in replay mode
    const CsiParams& p = cap->csi;
    if (!p.hardwareMacFilterPasses(h.transmitter))
    {
        ++counters_.framesDroppedMacFilter;
        return;
    }
    if (!((p.coreMask >> h.core) & 1) || !((p.nssMask >> h.stream) & 1))
    {
        ++counters_.pairsMasked;
        return;
    }
    if (opt_.convertReplayFormat && h.variant != opt_.format)
    {
        std::vector<std::complex<float>> csi(h.nfft());
        nexmon::decodeWords(d.data() + nexmon::csiOffset(), h.nfft(), csi.data());
        nexmon::DatagramHeader out = h;
        out.variant = opt_.format;
        out.chipId = opt_.format == NexmonHeaderVariant::UbiLocate ? 0 : nexmon::kChip4366c0;
        out.coreMask = p.coreMask;
        out.streamMask = p.nssMask;
        std::vector<uint8_t> converted;
        nexmon::encodeDatagram(out, csi.data(), converted);
        d.swap(converted);
    }
    ++counters_.framesEmitted;
    ++counters_.datagramsGenerated;
    emit(std::vector<uint8_t>(d), t);
}

std::vector<ScanEntry> Emulator::scan(WifiBand band)
{
    std::vector<ScanEntry> out;
    if (auto* s = dynamic_cast<ScenarioSource*>(source_.get()))
    {
        // The link budget of each AP at the robot's pose now: the RSSI of its next frame.
        const double t = std::clamp(simAt(uptime_s()), 0.0, s->sim.duration());
        const auto& txs = s->sim.scenario().transmitters;
        for (size_t i = 0; i < txs.size(); ++i)
        {
            if (txs[i].chanspec.band != band) continue;
            s->sim.synthesizeFrame(
                i, s->sim.firstFrameAtOrAfter(i, t), s->scratch, s->scratchTruth);
            ScanEntry e;
            e.ssid = txs[i].name;
            e.bssid = txs[i].mac;
            e.chanspec = txs[i].chanspec;
            e.rssi_dBm = s->scratchTruth.rssi_dBm;
            e.noise_dBm = int(std::lround(s->scratchTruth.rxPower_dBm - s->scratchTruth.snr_dB));
            if (e.rssi_dBm >= kMinScanRssi_dBm) out.push_back(e);
        }
    }
    else
        for (const auto& [mac, e] : seenInReplay_)
            if (e.chanspec.band == band) out.push_back(e);
    return out;
}

void Emulator::sendDueOdometry(double now)
{
    const auto* s = dynamic_cast<const ScenarioSource*>(source_.get());
    if (!odometrySender_ || !s) return;
    // The robot drives whatever the router does (reboots, channel changes): only the clock.
    const auto& odo = s->sim.odometry();
    while (nextOdometry_ < odo.size() && wallAt(odo[nextOdometry_].time_s) <= now)
    {
        const auto& o = odo[nextOdometry_];
        const std::string d =
            odometryDatagram(counters_.odometrySent, o.time_s, o.odometry, o.velocityLocal);
        if (odometrySender_->send(reinterpret_cast<const uint8_t*>(d.data()), d.size()))
            ++counters_.odometrySent;
        ++nextOdometry_;
    }
}

void Emulator::openTruth()
{
    const auto* s = dynamic_cast<const ScenarioSource*>(source_.get());
    std::error_code ec;
    fs::create_directories(opt_.truthDir, ec);
    const fs::path dir(opt_.truthDir);
    const std::string trajectoryPath = (dir / "trajectory_tum.txt").string();
    truthTrajectory_ = std::make_unique<std::ofstream>(trajectoryPath);
    if (!*truthTrajectory_)
        throw std::runtime_error(
            "cannot write the ground truth '" + trajectoryPath + "' (--truth-dir)" +
            (ec ? ": " + ec.message() : std::string()));
    *truthTrajectory_ << std::fixed
                      << "# ground truth of the robot base (world frame) on the receiver's clock: "
                         "unix time at which the emulated robot was at the pose (scenario '"
                      << s->sim.scenario().name << "', seed " << s->sim.scenario().seed
                      << "). TUM: t x y z qx qy qz qw\n";
    truthStep_ = std::max(s->sim.trajectory().timeStep(), 0.01);

    const std::string txPath = (dir / "transmitters.yaml").string();
    std::ofstream tx(txPath);
    if (!tx) throw std::runtime_error("cannot write the ground truth '" + txPath + "'");
    sim::writeTransmittersYaml(tx, s->sim.scenario());
}

void Emulator::writeDueTruth(double now)
{
    const auto* s = dynamic_cast<const ScenarioSource*>(source_.get());
    if (!truthTrajectory_ || !s || paused_) return;
    // Each sample is stamped with the wall-clock instant the simulated clock passes it, the
    // instant the datagrams of that simulated time are sent: the receiver's clock, whatever
    // the pauses, speed changes and loops before.
    const double simNow = std::min(simAt(now), s->sim.duration());
    bool wrote = false;
    for (double t; (t = double(nextTruthSample_) * truthStep_) <= simNow + 1e-9; ++nextTruthSample_)
    {
        const auto p = s->sim.trajectory().poseAt(t);
        *truthTrajectory_ << std::setprecision(6) << unixOrigin_ + wallAt(t) << " " << p.x << " "
                          << p.y << " 0 0 0 " << std::setprecision(9) << std::sin(p.phi / 2) << " "
                          << std::cos(p.phi / 2) << "\n";
        wrote = true;
    }
    // Readable while the emulator runs (a scorer may look during a live run).
    if (wrote && now - lastTruthFlush_ >= 0.5)
    {
        truthTrajectory_->flush();
        lastTruthFlush_ = now;
    }
}

void Emulator::processDue(double now)
{
    sendDueOdometry(now);
    writeDueTruth(now);
    refreshCaptures(now);
    double t = 0;
    for (int budget = kItemsPerIteration; budget > 0 && source_->peek(t); --budget)
    {
        const double due = wallAt(t);
        if (due > now) break;
        counters_.maxLag_s = std::max(counters_.maxLag_s, now - due);
        source_->consume(*this);
        if (itemsSent() >= opt_.maxDatagrams) break;
        refreshCaptures(now);  // a silence episode may have started
    }
    if (faults_.holding())
        faults_.releaseExpired(
            simAt(now),
            [this](const std::vector<uint8_t>& d) { emit(std::vector<uint8_t>(d), -1); });
}

double Emulator::nextWakeup(double now)
{
    double t = now + kMaxPollWait_s;
    double next = 0;
    if (source_->peek(next)) t = std::min(t, wallAt(next));
    if (const auto* s = dynamic_cast<const ScenarioSource*>(source_.get());
        odometrySender_ && s && nextOdometry_ < s->sim.odometry().size())
        t = std::min(t, wallAt(s->sim.odometry()[nextOdometry_].time_s));
    t = std::min(t, router_.nextTimedChange(now));
    if (silencedUntil_ > now) t = std::min(t, silencedUntil_);
    t = std::min(t, opt_.duration_s);
    if (nextScheduledReboot_ < opt_.rebootAt_s.size())
        t = std::min(t, opt_.rebootAt_s[nextScheduledReboot_]);
    if (opt_.statusPeriod_s > 0) t = std::min(t, lastStatusLine_ + opt_.statusPeriod_s);
    if (faults_.holding()) t = std::min(t, now + faults_.holdLimit_s / speed_);
    return t;
}

StopReason Emulator::run()
{
    stopReason_ = StopReason::Running;
    wallAnchor_ = uptime_s();
    lastStatusLine_ = wallAnchor_;
    std::vector<pollfd> fds;
    while (stopReason_ == StopReason::Running)
    {
        double now = uptime_s();
        while (nextScheduledReboot_ < opt_.rebootAt_s.size() &&
               opt_.rebootAt_s[nextScheduledReboot_] <= now)
        {
            ++nextScheduledReboot_;
            reboot();
        }
        processDue(now);

        if (stopRequested_)
            stopReason_ = StopReason::Requested;
        else if (now >= opt_.duration_s)
            stopReason_ = StopReason::Duration;
        else if (itemsSent() >= opt_.maxDatagrams)
            stopReason_ = StopReason::MaxDatagrams;
        else if (source_->ended(simAt(now)))
        {
            if (!opt_.loop)
                stopReason_ = StopReason::EndOfSource;
            else
            {
                writeDueTruth(now);  // up to the scenario's end
                source_->restart();
                nextOdometry_ = 0;
                nextTruthSample_ = 0;
                simAnchor_ = 0;
                wallAnchor_ = now;
                lastItemTime_ = 0;
                lastCsiTime_.clear();
                captureSignature_ = "(restart)";  // reconfigure the source
            }
        }
        if (stopReason_ != StopReason::Running) break;

        if (opt_.statusPeriod_s > 0 && now - lastStatusLine_ >= opt_.statusPeriod_s &&
            opt_.statusStream)
        {
            *opt_.statusStream << statusLine() << std::endl;
            lastStatusLine_ = now;
        }

        fds.clear();
        fds.push_back({wakePipe_[0], POLLIN, 0});
        if (control_) control_->appendPollFds(fds);
        // A serial line the terminal didn't take yet: retry soon (ptys don't poll POLLOUT
        // reliably while no reader has the slave open).
        const double wait = serial_ && serial_->pending()
                                ? std::min(0.005, std::max(0.0, nextWakeup(now) - uptime_s()))
                                : std::max(0.0, nextWakeup(now) - uptime_s());
        flushSerial();
        timespec ts;
        ts.tv_sec = time_t(wait);
        ts.tv_nsec = long((wait - double(ts.tv_sec)) * 1e9);
        if (::ppoll(fds.data(), fds.size(), &ts, nullptr) > 0)
        {
            if (fds[0].revents & POLLIN)
            {
                char buf[64];
                while (::read(wakePipe_[0], buf, sizeof(buf)) > 0)
                {
                }
            }
            if (control_) control_->handleEvents(fds, 1);
        }
    }
    faults_.flush([this](const std::vector<uint8_t>& d) { emit(std::vector<uint8_t>(d), -1); });
    // Lines not yet read from the serial port vanish when it closes: give the reader a moment
    // (bounded) to take them. The terminal moves written bytes to the reader's buffer
    // asynchronously, so "nothing unread" must hold for a while.
    if (serial_)
    {
        double drainedSince = -1;
        for (const double until = uptime_s() + 2.0; uptime_s() < until; ::usleep(5000))
        {
            flushSerial();
            const double t = uptime_s();
            if (serial_->pending() || serial_->unreadBytes())
                drainedSince = -1;
            else if (drainedSince < 0)
                drainedSince = t;
            else if (t - drainedSince >= 0.05)
                break;
        }
    }
    if (sentPcap_) sentPcap_->close();
    if (truthTrajectory_) truthTrajectory_->flush();
    // Answer the command that stopped us (emulator-ctl stop) before the socket goes away.
    const double drainUntil = uptime_s() + 0.5;
    while (control_ && control_->hasPendingAnswers() && uptime_s() < drainUntil)
    {
        fds.clear();
        fds.push_back({wakePipe_[0], POLLIN, 0});
        control_->appendPollFds(fds);
        if (::poll(fds.data(), fds.size(), 10) > 0) control_->handleEvents(fds, 1);
    }
    if (!opt_.stateDir.empty())
    {
        std::ofstream f(fs::path(opt_.stateDir) / "summary.json");
        f << statusJson() << "\n";
    }
    return stopReason_;
}

// ------------------------------------------------------------------------------------ control
void Emulator::reboot()
{
    const double now = uptime_s();
    router_.reboot(now);
    if (auto* s = dynamic_cast<ScenarioSource*>(source_.get())) s->sim.reboot();
    lastCsiTime_.clear();
    ++counters_.reboots;
    if (opt_.logCommands && opt_.statusStream)
        *opt_.statusStream << "[rt-ac86u-emulator] router rebooting (boot " << router_.bootCount()
                           << ")" << std::endl;
}

ToolResult Emulator::handleCommand(const Argv& argv)
{
    if (argv.empty()) return ToolResult::failure("empty command", 2);
    if (baseName(argv[0]) == "emulator-ctl") return control(Argv(argv.begin() + 1, argv.end()));
    const ToolResult r = router_.execute(argv, uptime_s());
    if (opt_.logCommands && opt_.statusStream)
    {
        std::string line;
        for (const auto& a : argv) line += (line.empty() ? "" : " ") + a;
        *opt_.statusStream << "[rt-ac86u-emulator] $ " << line << "  → exit " << r.exitCode
                           << std::endl;
    }
    return r;
}

ToolResult Emulator::control(const Argv& args)
{
    static const char* kHelp =
        "emulator-ctl VERB\n"
        "  status                      state and counters as JSON\n"
        "  faults [--loss P] [--duplicate P] [--reorder P] [--corrupt P]\n"
        "         [--silence-rate HZ] [--silence-length S]   change fault injection\n"
        "  reboot                      power-cycle the router (new phase offsets)\n"
        "  silence SECONDS             no CSI for that long\n"
        "  pause | resume              freeze / continue the simulated clock\n"
        "  speed X                     simulated seconds per wall-clock second\n"
        "  stop                        end the emulator (summary JSON on its stdout)\n";
    if (args.empty() || args[0] == "help" || args[0] == "--help")
        return args.empty() ? ToolResult::failure(kHelp, 2) : ToolResult::success(kHelp);
    const std::string& verb = args[0];
    const double now = uptime_s();
    auto number = [](const std::string& text, double& out)
    {
        try
        {
            size_t used = 0;
            out = std::stod(text, &used);
            return used == text.size() && std::isfinite(out);
        }
        catch (const std::exception&)
        {
            return false;
        }
    };
    if (verb == "status" && args.size() == 1) return ToolResult::success(statusJson() + "\n");
    if (verb == "faults")
    {
        FaultSettings s = faults_.settings();
        for (size_t i = 1; i < args.size(); ++i)
        {
            std::string key = args[i], value;
            if (const auto eq = key.find('='); eq != std::string::npos)
            {
                value = key.substr(eq + 1);
                key = key.substr(0, eq);
            }
            else if (i + 1 < args.size())
                value = args[++i];
            double v = 0;
            if (!number(value, v))
                return ToolResult::failure("emulator-ctl: " + key + " needs a number", 2);
            if (key == "--loss")
                s.loss = v;
            else if (key == "--duplicate")
                s.duplicate = v;
            else if (key == "--reorder")
                s.reorder = v;
            else if (key == "--corrupt")
                s.corrupt = v;
            else if (key == "--silence-rate")
                s.silenceRate_Hz = v;
            else if (key == "--silence-length")
                s.silenceLength_s = v;
            else
                return ToolResult::failure(
                    "emulator-ctl: unknown fault '" + key + "'\n" + kHelp, 2);
        }
        try
        {
            faults_.setSettings(s);
        }
        catch (const std::invalid_argument& e)
        {
            return ToolResult::failure(std::string("emulator-ctl: ") + e.what(), 2);
        }
        return ToolResult::success(faults_.settings().toJson() + "\n");
    }
    if (verb == "reboot" && args.size() == 1)
    {
        reboot();
        return ToolResult::success(
            "router rebooting (boot " + std::to_string(router_.bootCount()) + ")\n");
    }
    if (verb == "silence" && args.size() == 2)
    {
        double s = 0;
        if (!number(args[1], s) || s < 0 || s > 3600)
            return ToolResult::failure("emulator-ctl: silence needs seconds in [0, 3600]", 2);
        silencedUntil_ = now + s;
        return ToolResult::success();
    }
    if ((verb == "pause" || verb == "resume") && args.size() == 1)
    {
        reanchor(now);
        paused_ = verb == "pause";
        return ToolResult::success();
    }
    if (verb == "speed" && args.size() == 2)
    {
        double v = 0;
        if (!number(args[1], v) || !(v > 0 && v <= 1e6))
            return ToolResult::failure("emulator-ctl: speed must be in (0, 1e6]", 2);
        reanchor(now);
        speed_ = v;
        return ToolResult::success();
    }
    if (verb == "stop" && args.size() == 1)
    {
        requestStop();
        return ToolResult::success("stopping\n");
    }
    return ToolResult::failure(
        "emulator-ctl: unknown or malformed verb '" + verb + "'\n" + kHelp, 2);
}

std::string Emulator::statusJson() const
{
    const double now = uptime_s();
    JsonObject em;
    em.str("device", toString(opt_.device))
        .str("serial_port", serialDevice())
        .str("source", source_->kind())
        .str("source_path", opt_.replayFile.empty() ? opt_.scenarioFile : opt_.replayFile)
        .str("scenario", scenario() ? scenario()->name : std::string())
        .str("format", toString(opt_.format))
        .str("destination", sender_->destination().asString())
        .str("state_dir", opt_.stateDir)
        .str("truth_dir", opt_.truthDir)
        .raw("scenario_seed", scenario() ? std::to_string(scenario()->seed) : std::string("null"))
        .uint("fault_seed", opt_.faultSeed)
        .num("speed", speed_)
        .boolean("paused", paused_)
        .boolean("silenced", now < silencedUntil_)
        .num("uptime_s", now)
        .num("sim_time_s", simAt(now))
        // Where simulated time 0 fell on the receiver's clock (valid without pause or speed
        // changes): shifts wifi-sim's ground truth onto a recording's timestamps. The truth
        // folder (truth_dir) is already on that clock.
        .raw("unix_time_at_sim_zero", mrpt::format("%.6f", unixOrigin_ + wallAt(0)))
        .str("stop_reason", toString(stopReason_));
    std::vector<std::string> caps;
    for (const auto& c : captures_)
        caps.push_back(JsonObject()
                           .str("interface", c.interfaceName)
                           .str("chanspec", c.chanspec.asString())
                           .json());
    const auto& c = counters_;
    JsonObject dp;
    dp.uint("frames_heard", c.framesHeard)
        .uint("frames_emitted", c.framesEmitted)
        .uint("frames_dropped_mac_filter", c.framesDroppedMacFilter)
        .uint("frames_dropped_packet_filter", c.framesDroppedPacketFilter)
        .uint("frames_dropped_busy", c.framesDroppedBusy)
        .uint("frames_dropped_masks", c.framesDroppedMasks)
        .uint("frames_dropped_silence", c.framesDroppedSilence)
        .uint("pairs_masked", c.pairsMasked)
        .uint("datagrams_generated", c.datagramsGenerated)
        .uint("datagrams_sent", sender_->datagramsSent())
        .uint("bytes_sent", sender_->bytesSent())
        .uint("send_errors", sender_->sendErrors())
        .uint("datagrams_over_limit", c.datagramsOverLimit)
        .uint("replay_read", c.replayRead)
        .uint("replay_unparsable", c.replayUnparsable)
        .uint("replay_off_channel", c.replayOffChannel)
        .uint("reboots", c.reboots)
        .uint("rewinds", c.rewinds)
        .uint("odometry_sent", c.odometrySent)
        .uint("serial_lines_written", serial_ ? serial_->linesWritten() : 0)
        .uint("serial_lines_dropped", serial_ ? serial_->linesDropped() : 0)
        .num("max_lag_s", c.maxLag_s);
    JsonObject perTransmitter;
    for (const auto& [mac, n] : c.framesEmittedByTransmitter) perTransmitter.uint(mac, n);
    dp.raw("frames_emitted_by_transmitter", perTransmitter.json());
    JsonObject root;
    root.raw("emulator", em.json())
        .raw("router", router_.toJson(now))
        .raw("capturing", detail::jsonArray(caps))
        .raw("data_plane", dp.json())
        .raw("fault_settings", faults_.settings().toJson())
        .raw("faults", faults_.counters().toJson());
    return root.json();
}

std::string Emulator::statusLine() const
{
    const double now = uptime_s();
    const uint64_t sent = sender_->datagramsSent();
    std::ostringstream s;
    s.precision(1);
    s << std::fixed << "[rt-ac86u-emulator] t=" << now << "s sim=" << simAt(now)
      << "s boot=" << router_.bootCount() << " module=" << toString(router_.module())
      << " capture=";
    if (captures_.empty()) s << "none";
    for (const auto& c : captures_) s << c.interfaceName << "@" << c.chanspec.asString() << " ";
    const auto& f = faults_.counters();
    s << " frames=" << counters_.framesEmitted << " sent=" << sent << " lost=" << f.lost
      << " dup=" << f.duplicated << " reord=" << f.reordered << " corrupt=" << f.corruptedTotal()
      << " errors=" << sender_->sendErrors();
    s.precision(2);
    s << " lag_max=" << counters_.maxLag_s * 1e3 << "ms";
    return s.str();
}

}  // namespace mrpt_wifi::emulator
