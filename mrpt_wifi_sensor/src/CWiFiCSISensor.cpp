/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/system/string_utils.h>
#include <mrpt_wifi/obs/ChainStateRecorder.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>
#include <mrpt_wifi/sensor/LiveBearingWorker.h>
#include <mrpt_wifi/sensor/PcapIO.h>
#include <mrpt_wifi/sensor/UdpCsiReceiver.h>

#include <algorithm>
#include <iomanip>
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

uint32_t channelKey(const Chanspec& cs)
{
    return (uint32_t(cs.centerChannel) << 16) | cs.bandwidthMHz |
           (cs.band == WifiBand::Band5G ? 0x8000u : 0u);
}
}  // namespace

double CWiFiCSISensor::Counters::ChannelUse::framesLostEstimate() const
{
    const double withCsi_s = time_s - downtime_s;
    if (frames == 0 || withCsi_s <= 0) return 0.0;
    return double(frames) / withCsi_s * downtime_s;
}

CWiFiCSISensor::CWiFiCSISensor()
    : mrpt::system::COutputLogger("CWiFiCSISensor"),
      settings_(std::make_unique<CsiSensorSettings>())
{
    m_sensorLabel = "WIFI_CSI";
}

CWiFiCSISensor::~CWiFiCSISensor()
{
    if (settings_->hopping())
        MRPT_LOG_INFO_STREAM("[" << m_sensorLabel << "] " << channelScheduleSummary());
    bearings_.reset();
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
    *settings_ = loadCsiSensorSettings(c, section, m_sensorLabel);
    for (const auto& note : settings_->pathNotes)
        MRPT_LOG_WARN_STREAM("[" << m_sensorLabel << "] note: " << note);
    bearingProcessor_.reset();
    if (settings_->bearing.enabled())
    {
        try
        {
            bearingProcessor_ = makeLiveBearingProcessor(settings_->bearing);
        }
        catch (const std::exception& e)
        {
            throw std::invalid_argument("section '" + section + "': " + e.what());
        }
    }
    chainStates_.reset();
    if (settings_->recordChainStates)
    {
        // With live bearings, the recorded state ids are those of their calibration.
        if (bearingProcessor_)
        {
            const auto& pre = bearingProcessor_->preprocessor();
            chainStates_ = std::make_unique<ChainStateRecorder>(
                pre.options().chainStates, pre.calibration(), pre.rxArray().name);
        }
        else
            chainStates_ = std::make_unique<ChainStateRecorder>();
    }
}

void CWiFiCSISensor::initialize()
{
    auto& s = *settings_;
    s.assembler.sensorLabel = m_sensorLabel;
    assembler_ = std::make_unique<CsiFrameAssembler>(
        s.assembler, [this](CObservationWiFiCSI::Ptr&& f) { onFrame(std::move(f)); });
    lastStatus_ = lastScan_ = mrpt::Clock::now();
    startBearings();
    try
    {
        if (s.source == CsiSensorSettings::Source::Udp)
        {
            receiver_ = std::make_unique<UdpCsiReceiver>(s.udp);
            MRPT_LOG_INFO_STREAM(
                "[" << m_sensorLabel << "] listening on UDP " << s.udp.bindAddress << ":"
                    << receiver_->boundPort() << " (receive buffer "
                    << receiver_->receiveBufferBytes() / 1024 << " KiB)");
        }
        else if (s.source == CsiSensorSettings::Source::Live)
        {
            CsiLiveSourceOptions lo;
            lo.udpPort = s.udp.port;
            lo.baud = s.serialBaud;
            lo.sensorLabel = m_sensorLabel;
            lo.sensorPose = s.assembler.sensorPose;
            live_ = openLiveSource(s.liveSource, lo);
            MRPT_LOG_INFO_STREAM("[" << m_sensorLabel << "] capturing from " << live_->describe());
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

    if (s.piControl != CsiSensorSettings::PiControl::Off)
    {
        std::shared_ptr<CommandRunner> runner;
        if (s.piControl == CsiSensorSettings::PiControl::Local)
            runner = std::make_shared<LocalCommandRunner>(s.pi.toolDir);
        else
            runner = std::make_shared<ShellCommandRunner>(
                std::make_shared<SshRouterShell>(s.ssh), s.pi.toolDir);
        pi_ = std::make_unique<NexmonPiControl>(runner, s.pi);
        worker_ = std::thread([this] { workerLoop(); });
        std::string steps;
        for (const auto& argv : pi_->configureCommands(s.extraction))
        {
            steps += steps.empty() ? "" : "; ";
            for (size_t i = 0; i < argv.size(); ++i) steps += (i ? " " : "") + argv[i];
        }
        MRPT_LOG_INFO_STREAM(
            "[" << m_sensorLabel << "] configuring the Raspberry Pi's Nexmon CSI on "
                << pi_->describe() << ": " << steps);
        switchTarget_ = s.extraction.chanspec;
        switchRequested_ = mrpt::Clock::now();
        postJob(
            [this, extraction = s.extraction]
            {
                pi_->configure(extraction);
                postEvent(
                    [this, cs = extraction.chanspec]
                    {
                        {
                            std::lock_guard<std::mutex> lk(mutex_);
                            configured_ = cs;
                        }
                        MRPT_LOG_INFO_STREAM(
                            "[" << m_sensorLabel << "] Raspberry Pi configured: CSI on "
                                << cs.asString());
                    });
            });
        return;
    }
    if (!s.routerControl)
    {
        // Listening only; the host's own card may still scan for the record.
        if (s.scanWithHost && s.scanPeriod_s > 0)
        {
            worker_ = std::thread([this] { workerLoop(); });
            requestScan();
        }
        return;
    }
    router_ =
        std::make_unique<NexmonRouterControl>(std::make_shared<SshRouterShell>(s.ssh), s.setup);
    if (s.autoChannel) selector_ = std::make_unique<AccessPointSelector>(s.selector);
    worker_ = std::thread([this] { workerLoop(); });
    MRPT_LOG_INFO_STREAM(
        "[" << m_sensorLabel << "] configuring router " << router_->shell().describe() << ": "
            << router_->configureCommand(s.extraction));
    const auto extraction = s.extraction;
    const bool loadModule = s.loadModule;
    // A schedule with 2.4 GHz channels (or one starting there) needs that radio bridged too.
    bool bridge2G4 = extraction.chanspec.band == WifiBand::Band2G4;
    for (const auto& cs : s.channelSchedule) bridge2G4 |= cs.band == WifiBand::Band2G4;
    bridge2G4 |= s.scheduleFromScan;  // the scans may find 2.4 GHz channels
    switchTarget_ = extraction.chanspec;
    switchRequested_ = mrpt::Clock::now();
    if (s.hopping())
    {
        schedule_ = s.channelSchedule;
        hopInFlight_ = true;
        std::lock_guard<std::mutex> lk(mutex_);
        startVisit(extraction.chanspec, switchRequested_);
        visitIsSwitch_ = false;  // the set-up (ssh, module) is no switch
        std::string list;
        for (const auto& cs : schedule_) list += " " + cs.asString();
        MRPT_LOG_INFO_STREAM(
            "[" << m_sensorLabel << "] channel schedule:"
                << (s.scheduleFromScan ? std::string(" from the scans of both bands (") +
                                             extraction.chanspec.asString() + "'s first)"
                                       : list)
                << ", " << s.channelDwell_s << " s on each");
    }
    postJob(
        [this, extraction, loadModule, bridge2G4]
        {
            if (loadModule) router_->loadFirmwareModule(bridge2G4);
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
                    onChannelConfigured(cs);
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
    if (settings_->hopping() && router_) advanceSchedule(mrpt::Clock::now());
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
    else if (live_)
        live_->poll(
            [this](const uint8_t* d, size_t n, mrpt::Clock::time_point t, const std::string& src)
            { onDatagram(d, n, t, src); },
            [this](CObservationWiFiCSI::Ptr&& f) { onFrame(std::move(f)); },
            std::chrono::milliseconds(0));
    if (!assembler_) return;

    const auto now = mrpt::Clock::now();
    assembler_->flushExpired(now);
    deliverBearings();
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
            auto& seen = counters_.otherSourceAddresses;
            if (seen.size() < 4 && std::find(seen.begin(), seen.end(), src) == seen.end())
                seen.push_back(src);
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
            s.extraction.macFilter.empty() ||
            (!s.routerControl && s.piControl == CsiSensorSettings::PiControl::Off) ||
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
        {
            auto& use = counters_.channels[channelKey(frame->chanspec)];
            use.chanspec = frame->chanspec;
            ++use.frames;
        }
        if (chainStates_)
        {
            chainStates_->record(*frame);
            counters_.chainStateChanges = chainStates_->changes();
            counters_.chainsWithJumps = chainStates_->chainsWithJumps();
            for (const auto& n : chainStates_->takeNotices())
                MRPT_LOG_WARN_STREAM("[" << m_sensorLabel << "] chain states: " << n);
        }
        if (switchTarget_ && frame->chanspec.sameChannel(*switchTarget_))
        {
            measured = secondsBetween(switchRequested_, frame->timestamp);
            lastSwitchDowntime_ = measured;
            switchTarget_.reset();
            if (visitIsSwitch_)
            {
                auto& use = counters_.channels[channelKey(frame->chanspec)];
                use.downtime_s += *measured;
                ++use.measured;
                counters_.maxSwitchDowntime_s = std::max(counters_.maxSwitchDowntime_s, *measured);
            }
        }
    }
    if (measured)
        MRPT_LOG_INFO_FMT(
            "[%s] first frame on %s %.0f ms after the switch request", m_sensorLabel.c_str(),
            frame->chanspec.asString().c_str(), *measured * 1e3);
    if (bearings_)
        bearings_->submit(std::move(frame));  // comes back with its bearing: deliverBearings()
    else
        appendObservation(frame);
}

void CWiFiCSISensor::startBearings()
{
    if (!bearingProcessor_) return;
    const auto& s = *settings_;
    // With router control the channel is known now: check its calibration before any frame.
    std::optional<Chanspec> channel;
    if (s.routerControl && !s.hopping()) channel = s.extraction.chanspec;
    bearings_ =
        std::make_unique<LiveBearingWorker>(std::move(bearingProcessor_), s.bearing, channel);
    bearingStatusTime_ = mrpt::Clock::now();
    MRPT_LOG_INFO_STREAM(
        "[" << m_sensorLabel << "] live bearings: " << s.bearing.algorithm << " (queue "
            << s.bearing.queueLength << " frames), observations " << m_sensorLabel << "_AOA");
    deliverBearings();  // the start-up calibration report
}

void CWiFiCSISensor::deliverBearings()
{
    if (!bearings_) return;
    for (const auto& m : bearings_->takeMessages())
    {
        if (m.problem)
            MRPT_LOG_WARN_STREAM("[" << m_sensorLabel << "] bearings: " << m.text);
        else
            MRPT_LOG_INFO_STREAM("[" << m_sensorLabel << "] bearings: " << m.text);
    }
    std::vector<mrpt::obs::CObservation::Ptr> ready;
    bearings_->takeReady(ready);
    for (auto& o : ready) appendObservation(o);
}

std::string CWiFiCSISensor::bearingStatus()
{
    if (!bearings_) return {};
    const auto now = mrpt::Clock::now();
    const double period_s = secondsBetween(bearingStatusTime_, now);
    bearingStatusTime_ = now;
    const auto st = bearings_->stats();
    const auto lat = bearings_->takeLatency();
    char buf[256];
    std::snprintf(
        buf, sizeof(buf),
        " | bearings %.1f/s (%llu total), skipped %llu (+%llu), rejected %llu, latency p50 %.1f ms "
        "p99 %.1f ms",
        period_s > 0 ? double(st.bearings - bearingsAtLastStatus_) / period_s : 0.0,
        static_cast<unsigned long long>(st.bearings), static_cast<unsigned long long>(st.skipped),
        static_cast<unsigned long long>(st.skipped - skippedAtLastStatus_),
        static_cast<unsigned long long>(st.rejected), lat.p50_s * 1e3, lat.p99_s * 1e3);
    bearingsAtLastStatus_ = st.bearings;
    skippedAtLastStatus_ = st.skipped;
    std::string out = buf;
    if (st.calibrationErrors)
        out += ", calibration mismatches " + std::to_string(st.calibrationErrors);
    return out;
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
        const auto now = mrpt::Clock::now();
        startVisit(cs, now);
        visitIsSwitch_ = true;
        switchTarget_ = cs;
        switchRequested_ = now;
        settings_->extraction.macFilter = extraction.macFilter;
    }
    MRPT_LOG_INFO_STREAM(
        "[" << m_sensorLabel << "] channel switch to " << cs.asString() << ": " << reason);
    // The RT-AC86U has a radio per band: a schedule leaving a band stops its capture, so only
    // the channel visited is heard.
    std::optional<Chanspec> leaving;
    if (settings_->hopping())
        if (const auto current = configuredChannel(); current && current->band != cs.band)
            leaving = current;
    postJob(
        [this, extraction, leaving]
        {
            try
            {
                if (leaving) router_->stopCapture(*leaving);
                router_->configure(extraction);
            }
            catch (const std::exception&)
            {
                // The schedule tries again after a dwell (the error is reported as usual).
                postEvent(
                    [this]
                    {
                        hopInFlight_ = false;
                        dwellStart_ = mrpt::Clock::now();
                    });
                throw;
            }
            postEvent(
                [this, cs = extraction.chanspec]
                {
                    {
                        std::lock_guard<std::mutex> lk(mutex_);
                        configured_ = cs;
                        ++counters_.channelSwitches;
                    }
                    onChannelConfigured(cs);
                });
        });
}

void CWiFiCSISensor::requestScan()
{
    lastScan_ = mrpt::Clock::now();
    const bool host = settings_->scanWithHost;
    if (!router_ && !host) throw std::logic_error("requestScan: router_control is off");
    {
        std::lock_guard<std::mutex> lk(mutex_);
        if (scanQueued_) return;  // one at a time
        scanQueued_ = true;
    }
    const auto band = settings_->extraction.chanspec.band;
    // A schedule from the scans visits both bands, as a building's APs spread over them: each
    // radio scans its own band. Otherwise only the band being captured matters.
    std::vector<WifiBand> bands{band};
    if (settings_->scheduleFromScan) bands = {WifiBand::Band5G, WifiBand::Band2G4};
    std::string scanner = host ? "host:" + settings_->scanInterface : "router:";
    if (!host)
        for (size_t i = 0; i < bands.size(); ++i)
            scanner += (i ? "+" : "") + router_->interfaceFor(bands[i]);
    postJob(
        [this, bands, host, scanner]
        {
            std::vector<ScannedAccessPoint> aps;
            if (host)
                aps = scanWithHostInterface(
                    settings_->scanInterface, settings_->setup.commandTimeout_s);
            else
                for (const auto b : bands)
                {
                    auto heard = router_->scan(b);
                    aps.insert(aps.end(), heard.begin(), heard.end());
                }
            // Keep the bands asked for (the host card hears both).
            aps.erase(
                std::remove_if(
                    aps.begin(), aps.end(),
                    [&](const ScannedAccessPoint& ap) {
                        return std::find(bands.begin(), bands.end(), ap.chanspec.band) ==
                               bands.end();
                    }),
                aps.end());
            postEvent(
                [this, aps = std::move(aps), scanner]
                {
                    auto scan = CObservationWiFiScan::Create();
                    scan->timestamp = mrpt::Clock::now();
                    scan->sensorLabel = m_sensorLabel + "_SCAN";
                    scan->sensorPose = settings_->assembler.sensorPose;
                    scan->scanner = scanner;
                    scan->accessPoints = aps;
                    {
                        std::lock_guard<std::mutex> lk(mutex_);
                        ++counters_.scans;
                        scanQueued_ = false;
                    }
                    appendObservation(scan);
                    if (settings_->scheduleFromScan)
                    {
                        // The capture's band first, then the other.
                        auto options = settings_->selector;
                        options.band = settings_->extraction.chanspec.band;
                        auto channels = channelsFromScan(*scan, options);
                        options.band =
                            options.band == WifiBand::Band5G ? WifiBand::Band2G4 : WifiBand::Band5G;
                        for (const auto& cs : channelsFromScan(*scan, options))
                            channels.push_back(cs);
                        const bool same = channels.size() == schedule_.size() &&
                                          std::equal(
                                              channels.begin(), channels.end(), schedule_.begin(),
                                              [](const Chanspec& a, const Chanspec& b)
                                              { return a.sameChannel(b); });
                        if (!same)
                        {
                            std::string list;
                            for (const auto& cs : channels) list += " " + cs.asString();
                            MRPT_LOG_INFO_STREAM(
                                "[" << m_sensorLabel << "] channel schedule from the scan:"
                                    << (list.empty() ? " no access point passes the limits "
                                                       "(auto_min_rssi_dBm, auto_ssid): staying "
                                                       "on the current channel"
                                                     : list));
                            schedule_ = std::move(channels);
                        }
                    }
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
    if (c.chainsWithJumps || c.chainStateChanges)
        o << " | chain state changes " << c.chainStateChanges << " (" << c.chainsWithJumps
          << " chain" << (c.chainsWithJumps == 1 ? "" : "s") << " jumping)";
    if (c.scans) o << " | scans " << c.scans << ", switches " << c.channelSwitches;
    if (const auto d = lastSwitchDowntime())
        o << " | last switch downtime " << int(*d * 1000) << " ms";
    if (settings_->hopping()) o << " | " << channelScheduleSummary();
    o << bearingStatus();
    if (!lastError().empty()) o << " | last error: " << lastError();
    MRPT_LOG_INFO(o.str());
}

CWiFiCSISensor::NoFrameDiagnosis CWiFiCSISensor::diagnoseNoFrames(
    const Counters& before, double seconds) const
{
    const auto& s = *settings_;
    const auto now = counters();
    const std::string during = "in " + std::to_string(int(std::lround(seconds))) + " s";
    NoFrameDiagnosis d;
    if (now.framesDelivered > before.framesDelivered) return d;
    const uint64_t datagrams = now.datagrams - before.datagrams;
    const std::string dataPath =
        s.source == CsiSensorSettings::Source::Udp
            ? "UDP " + s.udp.bindAddress + ":" +
                  std::to_string(receiver_ ? receiver_->boundPort() : s.udp.port)
        : s.source == CsiSensorSettings::Source::Live ? "source " + s.liveSource
                                                      : "the replay of " + s.pcapFile;
    using Cause = NoFrameDiagnosis::Cause;
    if (datagrams == 0)
    {
        const std::string error = lastError();
        if (replay_ && replayFinished_)
        {
            d.cause = Cause::ReplayEnded;
            d.text = "[" + m_sensorLabel + "] " + dataPath + " ended";
        }
        else if (!error.empty() && (router_ || pi_))
        {
            d.cause = Cause::ControlFailed;
            d.text = "[" + m_sensorLabel + "] " +
                     (router_ ? "router control failed: " : "Raspberry Pi control failed: ") +
                     error + "; and no datagram arrived on " + dataPath + " " + during +
                     (router_ ? " (check it by hand: csi-router status -c YOUR.ini; "
                                "docs/troubleshooting.md lists the ssh causes)"
                              : "");
        }
        else if (!error.empty() && !receiver_ && !live_ && !replay_)
        {
            d.cause = Cause::NoDatagrams;
            d.text = "[" + m_sensorLabel + "] the data path could not be opened: " + error +
                     " (another program on udp_port " + std::to_string(s.udp.port) +
                     "? udp_bind_address an address of this computer?)";
        }
        else
        {
            d.cause = Cause::NoDatagrams;
            d.text = "[" + m_sensorLabel + "] no datagram at all on " + dataPath + " " + during +
                     ": " +
                     (s.source == CsiSensorSettings::Source::Udp
                          ? std::string(
                                s.routerControl
                                    ? (configuredChannel() ? "the router was configured"
                                                           : "the router's configuration has "
                                                             "not finished")
                                    : "router_control = false: nothing here configures the router "
                                      "(run csi-router configure -c YOUR.ini, or set "
                                      "router_control = true)") +
                                "; check that it streams to this computer (csi-router status; the "
                                "Nexmon datagrams go to UDP port 5500 on the router's LAN: this "
                                "computer must be on that LAN, udp_port must be the port they go "
                                "to, udp_bind_address must not exclude them) and that no firewall "
                                "drops UDP port " +
                                std::to_string(s.udp.port) + " (nft list ruleset, ufw status)"
                          : std::string("check the device and that it captures CSI"));
        }
        return d;
    }
    d.cause = Cause::NoMatchingFrames;
    const uint64_t other = now.fromOtherSources - before.fromOtherSources;
    const uint64_t mac = now.framesFilteredMac - before.framesFilteredMac;
    const uint64_t rssi = now.framesFilteredRssi - before.framesFilteredRssi;
    const uint64_t accepted = now.assembler.accepted - before.assembler.accepted;
    std::string text = "[" + m_sensorLabel + "] " + std::to_string(datagrams) + " datagrams on " +
                       dataPath + " " + during + " but no CSI frame passed: ";
    if (other == datagrams)
    {
        std::string seen;
        for (const auto& a : now.otherSourceAddresses) seen += (seen.empty() ? "" : ", ") + a;
        text += "all came from other addresses than router_address = " + s.routerAddress +
                " (seen: " + seen +
                "); set router_address to the address the CSI comes from (10.10.10.10 for "
                "Nexmon on an RT-AC86U), or leave it empty to accept any";
    }
    else if (accepted == 0)
        text += "none is a CSI datagram the decoder accepts (format = " +
                std::string(nexmon::toString(s.assembler.format)) + "; " +
                now.assembler.asString() +
                "): is another program sending to this port, or the firmware another variant?";
    else if (mac > 0 && mac >= rssi)
        text += std::to_string(mac) +
                " frames from transmitters that mac_filter (or the router's packet_mac_filter) "
                "excludes: widen mac_filter or check the access points' MAC addresses "
                "(csi-router scan)";
    else if (rssi > 0)
        text += std::to_string(rssi) +
                " frames weaker than min_rssi_dBm = " + std::to_string(s.minRssi_dBm) +
                ": lower it or move closer";
    else
        text +=
            "datagrams were accepted but formed no frame yet (core_mask / stream_mask "
            "expect chains that never arrive? " +
            now.assembler.asString() + ")";
    d.text = text;
    return d;
}

void CWiFiCSISensor::startVisit(const Chanspec& cs, mrpt::Clock::time_point t)
{
    // The visit being left: its time, and all of it without CSI if no frame came.
    if (visiting_)
    {
        auto& left = counters_.channels[channelKey(*visiting_)];
        const double stay_s = secondsBetween(visitStart_, t);
        left.time_s += stay_s;
        if (visitIsSwitch_ && switchTarget_ && switchTarget_->sameChannel(*visiting_))
        {
            left.downtime_s += stay_s;
            ++left.withoutFrames;
            // The mean counts it, so does the max.
            counters_.maxSwitchDowntime_s = std::max(counters_.maxSwitchDowntime_s, stay_s);
        }
    }
    visiting_ = cs;
    visitStart_ = t;
    auto& use = counters_.channels[channelKey(cs)];
    use.chanspec = cs;
    ++use.visits;
}

void CWiFiCSISensor::onChannelConfigured(const Chanspec& cs)
{
    if (!settings_->hopping()) return;
    hopInFlight_ = false;
    dwellStart_ = mrpt::Clock::now();
    std::lock_guard<std::mutex> lk(mutex_);
    // The first visit counts from the end of the set-up, which is no switch.
    if (!visitIsSwitch_ && visiting_ && visiting_->sameChannel(cs)) visitStart_ = dwellStart_;
}

void CWiFiCSISensor::advanceSchedule(mrpt::Clock::time_point now)
{
    if (hopInFlight_ || schedule_.empty()) return;
    const auto current = configuredChannel();
    if (!current) return;
    size_t at = schedule_.size();  // not in the schedule (a scan changed it): go to its first
    for (size_t i = 0; i < schedule_.size(); ++i)
        if (schedule_[i].sameChannel(*current)) at = i;
    if (at < schedule_.size() &&
        (schedule_.size() == 1 || secondsBetween(dwellStart_, now) < settings_->channelDwell_s))
        return;
    const Chanspec next = schedule_[at < schedule_.size() ? (at + 1) % schedule_.size() : 0];
    hopInFlight_ = true;
    {
        std::lock_guard<std::mutex> lk(mutex_);
        ++counters_.scheduleSwitches;
    }
    char reason[96];
    std::snprintf(
        reason, sizeof(reason), "channel schedule (%.1f s on %s)", secondsBetween(dwellStart_, now),
        current->asString().c_str());
    requestChannel(next, reason);
}

std::vector<Chanspec> CWiFiCSISensor::channelSchedule() const
{
    return schedule_;
}

std::string CWiFiCSISensor::channelScheduleSummary() const
{
    auto c = counters();
    {
        // The visit under way counts up to now.
        std::lock_guard<std::mutex> lk(mutex_);
        if (visiting_)
        {
            auto& use = c.channels[channelKey(*visiting_)];
            const double stay_s = secondsBetween(visitStart_, mrpt::Clock::now());
            use.time_s += stay_s;
            if (visitIsSwitch_ && switchTarget_ && switchTarget_->sameChannel(*visiting_))
                use.downtime_s += stay_s;
        }
    }
    uint64_t measured = 0, withoutFrames = 0;
    double downtime_s = 0, lost = 0, frames = 0;
    for (const auto& [key, use] : c.channels)
    {
        measured += use.measured;
        withoutFrames += use.withoutFrames;
        downtime_s += use.downtime_s;
        lost += use.framesLostEstimate();
        frames += double(use.frames);
    }
    const uint64_t visits = measured + withoutFrames;
    std::ostringstream o;
    o << std::fixed << std::setprecision(0) << "channel schedule: " << c.scheduleSwitches
      << " switches";
    if (visits)
        o << ", time without CSI per switch " << 1e3 * downtime_s / double(visits) << " ms mean, "
          << 1e3 * c.maxSwitchDowntime_s << " ms max";
    if (withoutFrames) o << ", " << withoutFrames << " visits without any frame";
    o << ", ~" << lost << " frames lost to switching (" << std::setprecision(1)
      << (frames + lost > 0 ? 100.0 * lost / (frames + lost) : 0.0) << " %); frames per channel:";
    for (const auto& [key, use] : c.channels)
        o << " " << use.chanspec.asString() << " " << use.frames << " (" << use.visits
          << " visits)";
    return o.str();
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
