/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/system/string_utils.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>
#include <mrpt_wifi/sensor/PcapIO.h>
#include <mrpt_wifi/sensor/UdpCsiReceiver.h>

#include <algorithm>
#include <set>
#include <sstream>

IMPLEMENTS_GENERIC_SENSOR(CWiFiCSISensor, mrpt_wifi)

namespace mrpt_wifi
{
namespace
{
double secondsBetween(mrpt::Clock::time_point a, mrpt::Clock::time_point b)
{
    return std::chrono::duration<double>(b - a).count();
}

/** Edit distance, to suggest the key a typo meant. */
size_t editDistance(const std::string& a, const std::string& b)
{
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i)
    {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j)
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

/** Every key a [section] of this driver may hold: CGenericSensor's, rawlog-grabber's, ours. */
const std::set<std::string>& knownKeys()
{
    static const std::set<std::string> keys = {
        // MRPT's own
        "driver", "process_rate", "max_queue_len", "grab_decimation", "sensorLabel",
        "rawlog-grabber-ignore",
        // pose of the receive array on the robot (m, deg)
        "pose_x", "pose_y", "pose_z", "pose_yaw", "pose_pitch", "pose_roll",
        // data path
        "source", "udp_bind_address", "udp_port", "udp_receive_buffer", "pcap_file", "pcap_speed",
        "router_address", "mac_filter", "min_rssi_dBm", "format", "overwritten_bins",
        "frame_timeout", "core_mask", "stream_mask", "status_period", "abort_on_error",
        // control path: WiROS's 'login', 'channel', 'packet', 'setup' groups
        "router_control", "login_host", "login_port", "login_user", "login_identity_file",
        "login_known_hosts", "login_accept_new_host_key", "login_password_env", "login_askpass",
        "login_connect_timeout", "ssh_multiplex", "command_timeout", "setup_load_module",
        "setup_module_path", "setup_bridge", "setup_interface_5g", "setup_interface_2g4", "channel",
        "packet_mac_filter", "packet_delay", "packet_first_byte",
        // transmitter mode
        "transmitter_mode", "transmitter_mac", "transmitter_rate_hz", "transmitter_streams",
        "transmitter_count",
        // scanning and automatic channel
        "scan_period", "scan_wait", "auto_channel", "auto_min_rssi_gain_dB", "auto_min_dwell_s",
        "auto_min_rssi_dBm", "auto_ssid", "auto_mac_filter"};
    return keys;
}

unsigned parseUnsigned(const std::string& text, const std::string& key, unsigned maxValue)
{
    try
    {
        size_t used = 0;
        const unsigned long v = std::stoul(text, &used, 0);  // 0x.. accepted
        if (used == text.size() && v <= maxValue) return unsigned(v);
    }
    catch (const std::exception&)
    {
    }
    throw std::invalid_argument(
        "key '" + key + "': '" + text + "' is not a number in 0.." + std::to_string(maxValue));
}

std::vector<std::string> splitList(const std::string& s)
{
    std::vector<std::string> parts;
    mrpt::system::tokenize(s, ", \t", parts);
    return parts;
}
}  // namespace

struct CWiFiCSISensor::Settings
{
    Source source = Source::Udp;
    UdpCsiReceiverOptions udp;
    std::string pcapFile;
    double pcapSpeed = 1.0;
    std::string routerAddress;
    std::vector<MacPattern> macFilter;
    int minRssi_dBm = -128;
    CsiFrameAssemblerOptions assembler;
    double statusPeriod_s = 10.0;
    bool abortOnError = false;

    bool routerControl = false;
    SshOptions ssh;
    RouterSetupOptions setup;
    bool loadModule = true;
    CsiExtractionSettings extraction;

    bool transmitterMode = false;
    TransmitterSettings transmitter;

    double scanPeriod_s = 0;
    bool autoChannel = false;
    bool autoMacFilter = true;
    AccessPointSelectorOptions selector;
};

CWiFiCSISensor::CWiFiCSISensor()
    : mrpt::system::COutputLogger("CWiFiCSISensor"), settings_(std::make_unique<Settings>())
{
    m_sensorLabel = "WIFI_CSI";
}

CWiFiCSISensor::~CWiFiCSISensor()
{
    {
        std::lock_guard<std::mutex> lk(mutex_);
        stopWorker_ = true;
        jobs_.clear();
    }
    jobReady_.notify_all();
    if (worker_.joinable()) worker_.join();
    if (router_ && settings_->transmitterMode)
    {
        try
        {
            router_->stopTransmitter();
        }
        catch (const std::exception& e)
        {
            MRPT_LOG_WARN_STREAM("could not stop the transmitter loop: " << e.what());
        }
    }
}

void CWiFiCSISensor::loadConfig_sensorSpecific(
    const mrpt::config::CConfigFileBase& c, const std::string& section)
{
    std::vector<std::string> keys;
    c.getAllKeys(section, keys);
    for (const auto& k : keys)
    {
        if (knownKeys().count(k)) continue;
        std::string best;
        size_t bestDistance = 4;
        for (const auto& known : knownKeys())
            if (const size_t d = editDistance(k, known); d < bestDistance)
                bestDistance = d, best = known;
        throw std::invalid_argument(
            "section '" + section + "': unknown key '" + k + "'" +
            (best.empty() ? std::string() : " (did you mean '" + best + "'?)") +
            "; see share/rawlog-grabber/ for the keys of CWiFiCSISensor");
    }

    auto& s = *settings_;
    const auto str = [&](const std::string& key, const std::string& def)
    { return mrpt::system::trim(c.read_string(section, key, def)); };
    try
    {
        s.assembler.sensorLabel = m_sensorLabel;
        s.assembler.sensorPose = mrpt::poses::CPose3D(
            c.read_double(section, "pose_x", 0), c.read_double(section, "pose_y", 0),
            c.read_double(section, "pose_z", 0),
            mrpt::DEG2RAD(c.read_double(section, "pose_yaw", 0)),
            mrpt::DEG2RAD(c.read_double(section, "pose_pitch", 0)),
            mrpt::DEG2RAD(c.read_double(section, "pose_roll", 0)));

        const std::string source = str("source", "udp");
        if (source == "udp")
            s.source = Source::Udp;
        else if (source == "pcap")
            s.source = Source::Pcap;
        else
            throw std::invalid_argument("key 'source': '" + source + "' (expected udp or pcap)");
        s.udp.bindAddress = str("udp_bind_address", "0.0.0.0");
        s.udp.port = uint16_t(parseUnsigned(str("udp_port", "5500"), "udp_port", 65535));
        s.udp.receiveBufferBytes = int(
            parseUnsigned(str("udp_receive_buffer", "16777216"), "udp_receive_buffer", 1u << 30));
        s.pcapFile = str("pcap_file", "");
        if (s.source == Source::Pcap && s.pcapFile.empty())
            throw std::invalid_argument("source = pcap needs key 'pcap_file'");
        s.pcapSpeed = c.read_double(section, "pcap_speed", 1.0);
        if (!(s.pcapSpeed > 0)) throw std::invalid_argument("key 'pcap_speed' must be > 0");
        s.routerAddress = str("router_address", "");
        s.macFilter.clear();
        for (const auto& p : splitList(str("mac_filter", "")))
            s.macFilter.push_back(MacPattern::fromString(p));
        s.minRssi_dBm = c.read_int(section, "min_rssi_dBm", -128);
        s.assembler.format = nexmon::formatHintFromString(str("format", "auto"));
        s.assembler.overwrittenBins =
            overwrittenBinPolicyFromString(str("overwritten_bins", "repair"));
        s.assembler.frameTimeout_s = c.read_double(section, "frame_timeout", 0.1);
        s.assembler.coreMask = uint8_t(parseUnsigned(str("core_mask", "0xf"), "core_mask", 0xF));
        s.assembler.streamMask =
            uint8_t(parseUnsigned(str("stream_mask", "0xf"), "stream_mask", 0xF));
        s.statusPeriod_s = c.read_double(section, "status_period", 10.0);
        s.abortOnError = c.read_bool(section, "abort_on_error", false);

        s.routerControl = c.read_bool(section, "router_control", false);
        s.ssh.host = str("login_host", s.ssh.host);
        s.ssh.port = parseUnsigned(str("login_port", "22"), "login_port", 65535);
        s.ssh.user = str("login_user", s.ssh.user);
        s.ssh.identityFile = str("login_identity_file", "");
        s.ssh.knownHostsFile = str("login_known_hosts", "");
        s.ssh.acceptNewHostKey = c.read_bool(section, "login_accept_new_host_key", false);
        s.ssh.passwordEnvVar = str("login_password_env", "");
        s.ssh.askpassProgram = str("login_askpass", "");
        s.ssh.connectTimeout_s = c.read_double(section, "login_connect_timeout", 5.0);
        s.ssh.multiplex = c.read_bool(section, "ssh_multiplex", true);
        s.setup.commandTimeout_s = c.read_double(section, "command_timeout", 10.0);
        s.loadModule = c.read_bool(section, "setup_load_module", true);
        s.setup.modulePath = str("setup_module_path", s.setup.modulePath);
        s.setup.bridge = str("setup_bridge", s.setup.bridge);
        s.setup.interface5G = str("setup_interface_5g", s.setup.interface5G);
        s.setup.interface2G4 = str("setup_interface_2g4", s.setup.interface2G4);
        s.setup.scanWait_s = c.read_double(section, "scan_wait", 3.0);
        s.extraction.chanspec = Chanspec::fromString(str("channel", "157/80"));
        s.extraction.coreMask = s.assembler.coreMask;
        s.extraction.streamMask = s.assembler.streamMask;
        s.extraction.macFilter.clear();
        for (const auto& m : splitList(str("packet_mac_filter", "")))
            s.extraction.macFilter.push_back(MacAddress::fromString(m));
        if (s.extraction.macFilter.size() > 4)
            throw std::invalid_argument(
                "key 'packet_mac_filter': the firmware takes at most 4 MACs");
        s.extraction.delay =
            uint16_t(parseUnsigned(str("packet_delay", "0"), "packet_delay", 0xFFFF));
        if (const auto b = str("packet_first_byte", ""); !b.empty())
            s.extraction.firstPacketByte = uint8_t(parseUnsigned(b, "packet_first_byte", 0xFF));

        s.transmitterMode = c.read_bool(section, "transmitter_mode", false);
        if (const auto m = str("transmitter_mac", ""); !m.empty())
            s.transmitter.source = MacAddress::fromString(m);
        s.transmitter.rate_Hz = c.read_double(section, "transmitter_rate_hz", 50.0);
        s.transmitter.streams =
            parseUnsigned(str("transmitter_streams", "1"), "transmitter_streams", 4);
        s.transmitter.count =
            parseUnsigned(str("transmitter_count", "1000"), "transmitter_count", 10000000);

        s.scanPeriod_s = c.read_double(section, "scan_period", 0.0);
        s.autoChannel = c.read_bool(section, "auto_channel", false);
        s.autoMacFilter = c.read_bool(section, "auto_mac_filter", true);
        s.selector.minRssiGain_dB = c.read_double(section, "auto_min_rssi_gain_dB", 6.0);
        s.selector.minDwell_s = c.read_double(section, "auto_min_dwell_s", 10.0);
        s.selector.minRssi_dBm = c.read_int(section, "auto_min_rssi_dBm", -85);
        s.selector.ssidFilter = str("auto_ssid", "");
        if ((s.autoChannel || s.scanPeriod_s > 0 || s.transmitterMode) && !s.routerControl)
            throw std::invalid_argument(
                "scan_period, auto_channel and transmitter_mode need router_control = true");
        if (s.autoChannel && !(s.scanPeriod_s > 0))
            throw std::invalid_argument("auto_channel = true needs scan_period > 0");
    }
    catch (const std::invalid_argument& e)
    {
        throw std::invalid_argument("section '" + section + "': " + e.what());
    }
}

void CWiFiCSISensor::initialize()
{
    auto& s = *settings_;
    s.assembler.sensorLabel = m_sensorLabel;
    assembler_ = std::make_unique<CsiFrameAssembler>(
        s.assembler, [this](CObservationWiFiCSI::Ptr&& f) { onFrame(std::move(f)); });
    lastStatus_ = lastScan_ = mrpt::Clock::now();
    try
    {
        if (s.source == Source::Udp)
        {
            receiver_ = std::make_unique<UdpCsiReceiver>(s.udp);
            MRPT_LOG_INFO_STREAM(
                "[" << m_sensorLabel << "] listening on UDP " << s.udp.bindAddress << ":"
                    << receiver_->boundPort() << " (receive buffer "
                    << receiver_->receiveBufferBytes() / 1024 << " KiB)");
        }
        else
        {
            replay_ = std::make_unique<PcapReader>(s.pcapFile);
            replayStartWall_ = mrpt::Clock::now();
            MRPT_LOG_INFO_STREAM(
                "[" << m_sensorLabel << "] replaying " << s.pcapFile << " at x" << s.pcapSpeed);
        }
    }
    catch (const std::exception& e)
    {
        reportControlError(std::string("data path: ") + e.what());
        if (s.abortOnError) throw;
        return;
    }
    m_state = ssWorking;

    if (!s.routerControl) return;
    router_ =
        std::make_unique<NexmonRouterControl>(std::make_shared<SshRouterShell>(s.ssh), s.setup);
    if (s.autoChannel) selector_ = std::make_unique<AccessPointSelector>(s.selector);
    worker_ = std::thread([this] { workerLoop(); });
    MRPT_LOG_INFO_STREAM(
        "[" << m_sensorLabel << "] configuring router " << router_->shell().describe() << ": "
            << router_->configureCommand(s.extraction));
    const auto extraction = s.extraction;
    const bool loadModule = s.loadModule;
    switchTarget_ = extraction.chanspec;
    switchRequested_ = mrpt::Clock::now();
    postJob(
        [this, extraction, loadModule]
        {
            if (loadModule) router_->loadFirmwareModule();
            router_->configure(extraction);
            postEvent(
                [this, cs = extraction.chanspec]
                {
                    {
                        std::lock_guard<std::mutex> lk(mutex_);
                        configured_ = cs;
                    }
                    MRPT_LOG_INFO_STREAM(
                        "[" << m_sensorLabel << "] router configured: CSI on " << cs.asString());
                });
        });
    if (s.transmitterMode)
    {
        const auto t = s.transmitter;
        const auto band = s.extraction.chanspec.band;
        postJob(
            [this, t, band]
            {
                router_->startTransmitter(t, band);
                postEvent(
                    [this]
                    { MRPT_LOG_INFO_STREAM("[" << m_sensorLabel << "] transmitter mode on"); });
            });
    }
    if (s.scanPeriod_s > 0) requestScan();
}

void CWiFiCSISensor::doProcess()
{
    runEvents();
    if (receiver_)
    {
        receiver_->receive(
            [this](const uint8_t* d, size_t n, mrpt::Clock::time_point t, const std::string& src)
            { onDatagram(d, n, t, src); },
            std::chrono::milliseconds(0));
        std::lock_guard<std::mutex> lk(mutex_);
        counters_.kernelDrops = receiver_->kernelDrops();
    }
    else if (replay_ && !replayFinished_)
        drainReplay();
    if (!assembler_) return;

    const auto now = mrpt::Clock::now();
    assembler_->flushExpired(now);
    {
        std::lock_guard<std::mutex> lk(mutex_);
        counters_.assembler = assembler_->stats();
    }
    if (settings_->scanPeriod_s > 0 && secondsBetween(lastScan_, now) >= settings_->scanPeriod_s)
        requestScan();
    if (settings_->statusPeriod_s > 0 &&
        secondsBetween(lastStatus_, now) >= settings_->statusPeriod_s)
    {
        lastStatus_ = now;
        logStatus();
    }
}

void CWiFiCSISensor::onDatagram(
    const uint8_t* data, size_t len, mrpt::Clock::time_point t, const std::string& src)
{
    {
        std::lock_guard<std::mutex> lk(mutex_);
        ++counters_.datagrams;
        if (!settings_->routerAddress.empty() && src != settings_->routerAddress)
        {
            ++counters_.fromOtherSources;
            return;
        }
    }
    assembler_->push(data, len, t, src);
}

void CWiFiCSISensor::onFrame(CObservationWiFiCSI::Ptr&& frame)
{
    const auto& s = *settings_;
    std::optional<double> measured;
    {
        std::lock_guard<std::mutex> lk(mutex_);
        const bool macOk = s.macFilter.empty() ||
                           std::any_of(
                               s.macFilter.begin(), s.macFilter.end(),
                               [&](const MacPattern& p) { return p.matches(frame->transmitter); });
        // The hardware filter matches only two bytes: the software filter finishes the job.
        const bool hwMacOk =
            s.extraction.macFilter.empty() || !s.routerControl ||
            std::count(
                s.extraction.macFilter.begin(), s.extraction.macFilter.end(), frame->transmitter);
        if (!macOk || !hwMacOk)
        {
            ++counters_.framesFilteredMac;
            return;
        }
        // Only the current header carries an RSSI.
        if (frame->headerVariant == NexmonHeaderVariant::Nexmon && frame->rssi_dBm < s.minRssi_dBm)
        {
            ++counters_.framesFilteredRssi;
            return;
        }
        ++counters_.framesDelivered;
        if (switchTarget_ && frame->chanspec == *switchTarget_)
        {
            measured = secondsBetween(switchRequested_, frame->timestamp);
            lastSwitchDowntime_ = measured;
            switchTarget_.reset();
        }
    }
    if (measured)
        MRPT_LOG_INFO_FMT(
            "[%s] first frame on %s %.0f ms after the switch request", m_sensorLabel.c_str(),
            frame->chanspec.asString().c_str(), *measured * 1e3);
    appendObservation(frame);
}

void CWiFiCSISensor::drainReplay()
{
    // Deliver every datagram whose recorded time has come, stamped at its replayed arrival.
    const auto now = mrpt::Clock::now();
    try
    {
        for (;;)
        {
            if (!replayHasPending_)
            {
                PcapUdpDatagram d;
                if (!replay_->next(d))
                {
                    replayFinished_ = true;
                    assembler_->flushAll();
                    MRPT_LOG_INFO_STREAM(
                        "[" << m_sensorLabel << "] replay of " << settings_->pcapFile
                            << " finished");
                    return;
                }
                if (replayStartCapture_ == mrpt::Clock::time_point())
                    replayStartCapture_ = d.timestamp;
                replayPending_.assign(d.payload, d.payload + d.payloadLength);
                replayPendingSource_ = d.sourceAddress;
                replayPendingTime_ =
                    replayStartWall_ +
                    std::chrono::duration_cast<mrpt::Clock::duration>(
                        (d.timestamp - replayStartCapture_) / settings_->pcapSpeed);
                replayHasPending_ = true;
            }
            if (replayPendingTime_ > now) return;  // not yet: keep it for a later call
            onDatagram(
                replayPending_.data(), replayPending_.size(), replayPendingTime_,
                replayPendingSource_);
            replayHasPending_ = false;
        }
    }
    catch (const std::exception& e)
    {
        replayFinished_ = true;
        assembler_->flushAll();
        reportControlError(std::string("replay: ") + e.what());
    }
}

void CWiFiCSISensor::requestChannel(const Chanspec& cs, const std::string& reason)
{
    if (!router_) throw std::logic_error("requestChannel: router_control is off");
    auto extraction = settings_->extraction;
    extraction.chanspec = cs;
    if (selector_ && settings_->autoMacFilter && selector_->locked())
        extraction.macFilter = {selector_->locked()->bssid};
    {
        std::lock_guard<std::mutex> lk(mutex_);
        switchTarget_ = cs;
        switchRequested_ = mrpt::Clock::now();
        settings_->extraction.macFilter = extraction.macFilter;
    }
    MRPT_LOG_INFO_STREAM(
        "[" << m_sensorLabel << "] channel switch to " << cs.asString() << ": " << reason);
    postJob(
        [this, extraction]
        {
            router_->configure(extraction);
            postEvent(
                [this, cs = extraction.chanspec]
                {
                    std::lock_guard<std::mutex> lk(mutex_);
                    configured_ = cs;
                    ++counters_.channelSwitches;
                });
        });
}

void CWiFiCSISensor::requestScan()
{
    lastScan_ = mrpt::Clock::now();
    if (!router_) throw std::logic_error("requestScan: router_control is off");
    {
        std::lock_guard<std::mutex> lk(mutex_);
        if (scanQueued_) return;  // one at a time
        scanQueued_ = true;
    }
    const auto band = settings_->extraction.chanspec.band;
    postJob(
        [this, band]
        {
            auto aps = router_->scan(band);
            postEvent(
                [this, aps = std::move(aps)]
                {
                    auto scan = CObservationWiFiScan::Create();
                    scan->timestamp = mrpt::Clock::now();
                    scan->sensorLabel = m_sensorLabel + "_SCAN";
                    scan->sensorPose = settings_->assembler.sensorPose;
                    scan->scanner =
                        "router:" + router_->interfaceFor(settings_->extraction.chanspec.band);
                    scan->accessPoints = aps;
                    {
                        std::lock_guard<std::mutex> lk(mutex_);
                        ++counters_.scans;
                        scanQueued_ = false;
                    }
                    appendObservation(scan);
                    if (!selector_) return;
                    const double t = mrpt::Clock::toDouble(scan->timestamp);
                    if (auto decision = selector_->onScan(*scan, t))
                        requestChannel(decision->target.chanspec, decision->reason);
                });
        });
}

void CWiFiCSISensor::postJob(std::function<void()> job)
{
    {
        std::lock_guard<std::mutex> lk(mutex_);
        jobs_.push_back(std::move(job));
    }
    jobReady_.notify_one();
}

void CWiFiCSISensor::postEvent(std::function<void()> event)
{
    std::lock_guard<std::mutex> lk(mutex_);
    events_.push_back(std::move(event));
}

void CWiFiCSISensor::workerLoop()
{
    for (;;)
    {
        std::function<void()> job;
        {
            std::unique_lock<std::mutex> lk(mutex_);
            jobReady_.wait(lk, [this] { return stopWorker_ || !jobs_.empty(); });
            if (stopWorker_) return;
            job = std::move(jobs_.front());
            jobs_.pop_front();
        }
        try
        {
            job();
        }
        catch (const std::exception& e)
        {
            postEvent([this, what = std::string(e.what())] { reportControlError(what); });
        }
    }
}

void CWiFiCSISensor::runEvents()
{
    std::deque<std::function<void()>> events;
    {
        std::lock_guard<std::mutex> lk(mutex_);
        events.swap(events_);
    }
    for (auto& e : events) e();
}

void CWiFiCSISensor::reportControlError(const std::string& what)
{
    {
        std::lock_guard<std::mutex> lk(mutex_);
        lastError_ = what;
        ++counters_.controlErrors;
        scanQueued_ = false;
    }
    m_state = ssError;
    MRPT_LOG_ERROR_STREAM("[" << m_sensorLabel << "] " << what);
    if (settings_->abortOnError) throw std::runtime_error("[" + m_sensorLabel + "] " + what);
}

void CWiFiCSISensor::logStatus()
{
    const auto c = counters();
    std::ostringstream o;
    o << "[" << m_sensorLabel << "] "
      << (m_state == ssWorking ? "working"
          : m_state == ssError ? "ERROR"
                               : "initializing");
    if (const auto cs = configuredChannel()) o << ", channel " << cs->asString();
    o << " | datagrams " << c.datagrams << " | frames delivered " << c.framesDelivered
      << " (MAC-filtered " << c.framesFilteredMac << ", RSSI-filtered " << c.framesFilteredRssi
      << ") | " << c.assembler.asString() << " | kernel drops " << c.kernelDrops;
    if (c.fromOtherSources) o << " | other sources " << c.fromOtherSources;
    if (c.scans) o << " | scans " << c.scans << ", switches " << c.channelSwitches;
    if (const auto d = lastSwitchDowntime())
        o << " | last switch downtime " << int(*d * 1000) << " ms";
    if (!lastError().empty()) o << " | last error: " << lastError();
    MRPT_LOG_INFO(o.str());
}

CWiFiCSISensor::Counters CWiFiCSISensor::counters() const
{
    std::lock_guard<std::mutex> lk(mutex_);
    return counters_;
}

std::string CWiFiCSISensor::lastError() const
{
    std::lock_guard<std::mutex> lk(mutex_);
    return lastError_;
}

std::optional<Chanspec> CWiFiCSISensor::configuredChannel() const
{
    std::lock_guard<std::mutex> lk(mutex_);
    return configured_;
}

std::optional<double> CWiFiCSISensor::lastSwitchDowntime() const
{
    std::lock_guard<std::mutex> lk(mutex_);
    return lastSwitchDowntime_;
}

}  // namespace mrpt_wifi
