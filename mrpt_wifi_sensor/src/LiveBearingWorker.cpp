/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/ConfigPaths.h>
#include <mrpt_wifi/obs/bearing/BearingChainConfig.h>
#include <mrpt_wifi/sensor/LiveBearingWorker.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <sstream>

namespace mrpt_wifi
{
namespace
{
namespace fs = std::filesystem;

std::string defaultArrayFile()
{
    return config::findDataFile("arrays/rt-ac86u.yaml");
}

/** Runs `f`, prefixing any error with the key it came from. */
template <typename F>
auto forKey(const std::string& key, F&& f) -> decltype(f())
{
    try
    {
        return f();
    }
    catch (const std::exception& e)
    {
        throw std::invalid_argument("key '" + key + "': " + e.what());
    }
}

/** "2024-05-02", "2024-05-02T10:31:00Z": seconds since 1970 (UTC), nullopt if not a date. */
std::optional<double> parseIsoDate(const std::string& text)
{
    std::tm tm{};
    int n = 0;
    if (std::sscanf(text.c_str(), "%4d-%2d-%2d%n", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &n) < 3 ||
        n != 10)
        return std::nullopt;
    std::sscanf(text.c_str() + n, "T%2d:%2d:%2d", &tm.tm_hour, &tm.tm_min, &tm.tm_sec);
    tm.tm_year -= 1900;
    tm.tm_mon -= 1;
    const time_t t = timegm(&tm);
    if (t == time_t(-1)) return std::nullopt;
    return double(t);
}

double percentile(std::vector<double>& v, double p)
{
    const size_t i = std::min(v.size() - 1, size_t(std::ceil(p * double(v.size())) - 1));
    std::nth_element(v.begin(), v.begin() + long(i), v.end());
    return v[i];
}
}  // namespace

std::unique_ptr<bearing::BearingProcessor> makeLiveBearingProcessor(const LiveBearingSettings& s)
{
    if (!s.enabled()) throw std::logic_error("makeLiveBearingProcessor: bearing_algorithm is off");
    // The same steps, in the same order, as csi-bearings.
    // `bearing_options`: a csi-bearings --config file, or inline estimator options `{k: v}`.
    const bool inlineOptions = !s.optionsFile.empty() && s.optionsFile.front() == '{';
    const auto cfg = forKey(
        "bearing_options",
        [&]
        {
            return bearing::loadBearingChainConfig(
                inlineOptions ? std::string() : s.optionsFile, s.algorithm);
        });
    mrpt::containers::yaml params = mrpt::containers::yaml::Map();
    if (!cfg.estimatorParams.isNullNode()) params = cfg.estimatorParams;
    if (inlineOptions)
        params = forKey(
            "bearing_options", [&] { return mrpt::containers::yaml::FromText(s.optionsFile); });
    auto estimator = forKey(
        "bearing_algorithm",
        [&]
        {
            auto e = bearing::createEstimator(s.algorithm, params);
            if (e->syntheticAperture())
                throw std::invalid_argument(
                    "'" + s.algorithm +
                    "' needs the peers' recordings of this robot and its odometry, which the "
                    "live sensor does not have: run csi-bearings on the merged rawlog");
            return e;
        });
    const std::string arrayPath = s.arrayFile.empty() ? defaultArrayFile() : s.arrayFile;
    AntennaArray rxArray =
        forKey("bearing_array", [&] { return AntennaArray::fromYamlFile(arrayPath); });
    CalibrationStore calib;
    if (!s.calibration.empty())
        calib =
            forKey("bearing_calibration", [&] { return CalibrationStore::open(s.calibration); });
    auto processor = std::make_unique<bearing::BearingProcessor>(
        CsiPreprocessor(cfg.pre, std::move(rxArray), std::move(calib)), std::move(estimator),
        cfg.window);
    forKey(
        "bearing_tx_arrays",
        [&]
        {
            for (const auto& t : s.txArrays)
            {
                const auto eq = t.find('=');
                if (eq == std::string::npos)
                    processor->setDefaultTransmitterArray(AntennaArray::fromYamlFile(t));
                else
                    processor->setTransmitterArray(
                        MacAddress::fromString(t.substr(0, eq)),
                        AntennaArray::fromYamlFile(t.substr(eq + 1)));
            }
            return 0;
        });
    return processor;
}

LiveBearingWorker::LiveBearingWorker(
    std::unique_ptr<bearing::BearingProcessor> processor, const LiveBearingSettings& settings,
    std::optional<Chanspec> configuredChannel)
    : processor_(std::move(processor)), settings_(settings)
{
    if (!processor_) throw std::invalid_argument("LiveBearingWorker: no processor");
    if (configuredChannel)
        messages_.push_back(describeCalibration(
            *processor_, *configuredChannel, unsigned(processor_->preprocessor().rxArray().size()),
            settings_.calibrationMaxAge_days, mrpt::Clock::now()));
    thread_ = std::thread([this] { run(); });
}

LiveBearingWorker::~LiveBearingWorker()
{
    {
        std::lock_guard<std::mutex> lk(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
}

void LiveBearingWorker::submit(CObservationWiFiCSI::Ptr frame)
{
    auto slot = std::make_shared<Slot>();
    slot->frame = std::move(frame);
    slot->submitted = mrpt::Clock::now();
    {
        std::lock_guard<std::mutex> lk(mutex_);
        ++stats_.submitted;
        order_.push_back(slot);
        if (work_.size() >= std::max<size_t>(1, settings_.queueLength))
        {
            slot->done = true;  // delivered without a bearing
            ++stats_.skipped;
            return;
        }
        work_.push_back(slot);
    }
    wake_.notify_one();
}

void LiveBearingWorker::addOdometry(mrpt::Clock::time_point t, const mrpt::math::TPose2D& odometry)
{
    // Bounded while no frame comes: the chain keeps only the last seconds of odometry anyway.
    constexpr size_t kMaxPending = 4096;
    std::lock_guard<std::mutex> lk(mutex_);
    if (odometry_.size() >= kMaxPending)
        odometry_.erase(odometry_.begin(), odometry_.begin() + long(kMaxPending / 2));
    odometry_.emplace_back(t, odometry);
}

void LiveBearingWorker::takeReady(std::vector<mrpt::obs::CObservation::Ptr>& out)
{
    std::lock_guard<std::mutex> lk(mutex_);
    while (!order_.empty() && order_.front()->done)
    {
        auto& s = *order_.front();
        out.push_back(std::move(s.frame));
        for (auto& e : s.extra) out.push_back(std::move(e));
        order_.pop_front();
    }
}

bool LiveBearingWorker::waitIdle(double timeout_s)
{
    std::unique_lock<std::mutex> lk(mutex_);
    return idle_.wait_for(
        lk, std::chrono::duration<double>(timeout_s),
        [this] { return work_.empty() && busy_ == 0; });
}

void LiveBearingWorker::run()
{
    for (;;)
    {
        std::shared_ptr<Slot> slot;
        std::vector<std::pair<mrpt::Clock::time_point, mrpt::math::TPose2D>> odometry;
        {
            std::unique_lock<std::mutex> lk(mutex_);
            wake_.wait(lk, [this] { return stop_ || !work_.empty(); });
            if (stop_) return;
            slot = std::move(work_.front());
            work_.pop_front();
            ++busy_;
            odometry.swap(odometry_);
            stats_.odometry += odometry.size();
        }
        // The chain is this thread's alone: the odometry joins it here, before the frame.
        for (const auto& [t, pose] : odometry) processor_->addOdometry(t, pose);
        estimate(*slot);
        {
            std::lock_guard<std::mutex> lk(mutex_);
            slot->done = true;
            --busy_;
            // Taken by the status lines; without them (status_period = 0) only the newest
            // are kept, or a long run would keep one per frame.
            if (latencies_s_.size() >= kMaxLatencySamples)
                latencies_s_.erase(
                    latencies_s_.begin(), latencies_s_.begin() + long(kMaxLatencySamples / 2));
            latencies_s_.push_back(
                std::chrono::duration<double>(mrpt::Clock::now() - slot->submitted).count());
        }
        idle_.notify_all();
    }
}

void LiveBearingWorker::estimate(Slot& slot)
{
    const CObservationWiFiCSI& csi = *slot.frame;
    if ((!lastChannel_ || *lastChannel_ != csi.chanspec.raw) &&
        reportedChannels_.insert(csi.chanspec.raw).second)
    {
        lastChannel_ = csi.chanspec.raw;
        // The calibration holds one phase per array element, which need not be one per row (an
        // array naming some of the cores); a frame lacking the array's cores is said at once.
        std::vector<unsigned> rows;
        const auto fits = processor_->preprocessor().elementRows(csi, rows);
        auto m = fits == RejectReason::Accepted
                     ? describeCalibration(
                           *processor_, csi.chanspec, unsigned(rows.size()),
                           settings_.calibrationMaxAge_days, mrpt::Clock::now())
                     : Message{true, processor_->preprocessor().coreMismatchMessage(csi)};
        m.text = "first frame on " + csi.chanspec.asString() + ": " + m.text;
        std::lock_guard<std::mutex> lk(mutex_);
        messages_.push_back(std::move(m));
    }
    RejectReason why = RejectReason::Accepted;
    CObservationWiFiBearing::Ptr b;
    bool calibrationError = false;
    try
    {
        b = processor_->process(csi, &why);
    }
    catch (const CalibrationError&)
    {
        calibrationError = true;  // reported once per channel by describeCalibration()
    }
    std::lock_guard<std::mutex> lk(mutex_);
    ++stats_.estimated;
    if (calibrationError)
        ++stats_.calibrationErrors;
    else if (why != RejectReason::Accepted)
        ++stats_.rejected;
    if (!b) return;
    ++stats_.bearings;
    slot.extra.push_back(b);
    slot.extra.push_back(b->asBearingRange());
}

LiveBearingWorker::Stats LiveBearingWorker::stats() const
{
    std::lock_guard<std::mutex> lk(mutex_);
    return stats_;
}

LiveBearingWorker::Latency LiveBearingWorker::takeLatency()
{
    std::vector<double> v;
    {
        std::lock_guard<std::mutex> lk(mutex_);
        v.swap(latencies_s_);
    }
    Latency l;
    l.samples = v.size();
    if (v.empty()) return l;
    l.max_s = *std::max_element(v.begin(), v.end());
    l.p99_s = percentile(v, 0.99);
    l.p50_s = percentile(v, 0.50);
    return l;
}

std::vector<LiveBearingWorker::Message> LiveBearingWorker::takeMessages()
{
    std::lock_guard<std::mutex> lk(mutex_);
    std::vector<Message> out;
    out.swap(messages_);
    return out;
}

LiveBearingWorker::Message LiveBearingWorker::describeCalibration(
    bearing::BearingProcessor& processor, const Chanspec& cs, unsigned nRx, double maxAge_days,
    mrpt::Clock::time_point now)
{
    auto& pre = processor.preprocessor();
    const CalibrationStore& store = pre.calibration();
    const std::string device = pre.rxArray().name;
    const std::string uncal = pre.options().requireCalibration
                                  ? "frames on it get no bearing (require_calibration)"
                                  : "bearings on it are uncalibrated";
    if (store.empty()) return {true, "no bearing_calibration: " + uncal};
    const PhaseCalibration* c = nullptr;
    try
    {
        c = store.find(device, cs, nRx);
    }
    catch (const CalibrationError& e)
    {
        return {true, std::string(e.what()) + "; frames on " + cs.asString() + " get no bearing"};
    }
    if (!c) return {true, store.missingChannelAdvice(device, cs) + "; " + uncal};
    const std::string file = c->sourcePath.empty() ? store.path() : c->sourcePath;
    if (maxAge_days > 0)
    {
        const auto made = parseIsoDate(c->date);
        if (!made)
            return {
                true, "calibration '" + file + "' has no date ('" + c->date +
                          "'): cannot tell whether it is stale"};
        const double age_days = (mrpt::Clock::toDouble(now) - *made) / 86400.0;
        if (age_days > maxAge_days)
        {
            char buf[64];
            std::snprintf(buf, sizeof(buf), "%.0f days", age_days);
            return {
                true, "calibration '" + file + "' is stale: made " + c->date + ", " + buf +
                          " ago (the chain phases change at every router boot; recalibrate, see "
                          "share/calibration/README.md)"};
        }
    }
    return {false, "calibration '" + file + "' (" + c->date + ")"};
}

}  // namespace mrpt_wifi
