// Live bearings (LiveBearingWorker, the sensor's bearing_* keys): the same observations as the
// offline chain, in order; a full queue skips estimation without holding up capture; clear
// configuration errors; calibration reports per channel.
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/obs/CObservationBearingRange.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>
#include <mrpt_wifi/sensor/LiveBearingWorker.h>

#include <chrono>
#include <ctime>
#include <future>

#include "SensorConfigError.h"
#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
std::vector<CObservationWiFiCSI::Ptr> sampleFrames()
{
    std::vector<CObservationWiFiCSI::Ptr> frames;
    CsiFileReadOptions o;
    o.assembler.sensorLabel = "CSI";
    readCsiFrames(
        test::sourceDir() + "/share/samples/sample_4x4_80mhz.pcap", o,
        [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(std::move(f)); });
    return frames;
}

LiveBearingSettings settingsFor(const std::string& algo)
{
    LiveBearingSettings s;
    s.algorithm = algo;
    return s;
}

void expectSameBearing(const CObservationWiFiBearing& a, const CObservationWiFiBearing& b)
{
    EXPECT_EQ(a.sensorLabel, b.sensorLabel);
    EXPECT_EQ(a.timestamp, b.timestamp);
    EXPECT_EQ(a.transmitter, b.transmitter);
    EXPECT_EQ(a.algorithm, b.algorithm);
    EXPECT_EQ(a.aoa_rad, b.aoa_rad);
    EXPECT_EQ(a.aoaStd_rad, b.aoaStd_rad);
    EXPECT_EQ(a.aod_rad, b.aod_rad);
    EXPECT_EQ(a.delay_s, b.delay_s);
    EXPECT_EQ(a.quality, b.quality);
    EXPECT_EQ(a.framesUsed, b.framesUsed);
}

/** An estimator that waits for the test before each estimate (to fill the queue on purpose). */
class GatedEstimator : public bearing::BearingEstimator
{
public:
    explicit GatedEstimator(std::shared_future<void> gate)
        : inner_(bearing::createEstimator("aoa_only")), gate_(std::move(gate))
    {
    }
    std::string name() const override { return "gated"; }
    std::string description() const override { return "aoa_only after a gate"; }
    std::vector<std::string> parameterKeys() const override { return {}; }
    bool estimate(
        const std::vector<const CleanCsi*>& frames, const bearing::EstimatorContext& ctx,
        bearing::BearingResult& result) override
    {
        entered.set_value();
        entered = std::promise<void>();
        gate_.wait();
        return inner_->estimate(frames, ctx, result);
    }
    std::promise<void> entered;

private:
    std::unique_ptr<bearing::BearingEstimator> inner_;
    std::shared_future<void> gate_;
};

PhaseCalibration zeroCalibration(const std::string& chanspec, const std::string& date)
{
    PhaseCalibration c;
    c.device = "rt-ac86u";
    c.chanspec = Chanspec::fromString(chanspec);
    c.date = date;
    c.method = "test";
    c.subcarriers = {-122, 122};
    c.phases_rad.assign(4, std::vector<double>(2, 0.0));
    return c;
}

std::string today()
{
    const std::time_t t = std::time(nullptr);
    char buf[32];
    std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
    return buf;
}

std::string configError(const std::string& keys)
{
    return test::sensorConfigError("[CSI]\nprocess_rate = 100\n" + keys);
}
}  // namespace

TEST(LiveBearingWorker, SameObservationsAsTheOfflineChainInOrder)
{
    const auto frames = sampleFrames();
    ASSERT_EQ(frames.size(), 22u);
    for (const std::string algo : {"aoa_only", "fft"})
    {
        SCOPED_TRACE(algo);
        auto offline = makeLiveBearingProcessor(settingsFor(algo));
        LiveBearingWorker worker(makeLiveBearingProcessor(settingsFor(algo)), settingsFor(algo));
        std::vector<mrpt::obs::CObservation::Ptr> expected, live;
        for (const auto& f : frames)
        {
            expected.push_back(f);
            if (auto b = offline->process(*f))
            {
                expected.push_back(b);
                expected.push_back(b->asBearingRange());
            }
            worker.submit(f);
        }
        ASSERT_TRUE(worker.waitIdle(30.0));
        worker.takeReady(live);
        const auto st = worker.stats();
        EXPECT_EQ(st.submitted, 22u);
        EXPECT_EQ(st.skipped, 0u);
        EXPECT_GT(st.bearings, 0u);
        ASSERT_EQ(live.size(), expected.size());
        for (size_t i = 0; i < live.size(); ++i)
        {
            ASSERT_EQ(live[i]->GetRuntimeClass(), expected[i]->GetRuntimeClass()) << i;
            EXPECT_EQ(live[i]->sensorLabel, expected[i]->sensorLabel) << i;
            if (auto b = std::dynamic_pointer_cast<CObservationWiFiBearing>(live[i]))
            {
                EXPECT_EQ(b->sensorLabel, "CSI_AOA");
                expectSameBearing(
                    *b, *std::dynamic_pointer_cast<CObservationWiFiBearing>(expected[i]));
            }
            else if (auto csi = std::dynamic_pointer_cast<CObservationWiFiCSI>(live[i]))
            {
                EXPECT_EQ(csi, expected[i]);  // the very frame, not a copy
            }
        }
        const auto lat = worker.takeLatency();
        EXPECT_EQ(lat.samples, 22u);
        EXPECT_LE(lat.p50_s, lat.p99_s);
        EXPECT_EQ(worker.takeLatency().samples, 0u);  // since the last call
    }
}

TEST(LiveBearingWorker, OdometryLimitsTheWindowAsInTheOfflineChain)
{
    // The robot moves 0.1 m per frame (frames of the 4 APs interleave): given the odometry, a
    // window holds only the frames within 0.15 m of the newest, in the worker exactly as in
    // csi-bearings' chain; without it, every frame of the window is combined.
    const auto frames = sampleFrames();
    auto settings = settingsFor("aoa_only");
    settings.optionsFile = "{window: 8}";
    auto offline = makeLiveBearingProcessor(settings);
    auto still = makeLiveBearingProcessor(settings);
    LiveBearingWorker worker(makeLiveBearingProcessor(settings), settings);
    std::vector<CObservationWiFiBearing::Ptr> expected, unlimited;
    for (size_t i = 0; i < frames.size(); ++i)
    {
        const mrpt::math::TPose2D odometry(0.1 * double(i), 0, 0);
        offline->addOdometry(frames[i]->timestamp, odometry);
        worker.addOdometry(frames[i]->timestamp, odometry);
        if (auto b = offline->process(*frames[i])) expected.push_back(b);
        if (auto b = still->process(*frames[i])) unlimited.push_back(b);
        worker.submit(frames[i]);
    }
    ASSERT_TRUE(worker.waitIdle(30.0));
    std::vector<mrpt::obs::CObservation::Ptr> out;
    worker.takeReady(out);
    std::vector<CObservationWiFiBearing::Ptr> live;
    for (const auto& o : out)
        if (auto b = std::dynamic_pointer_cast<CObservationWiFiBearing>(o)) live.push_back(b);
    EXPECT_EQ(worker.stats().odometry, frames.size());
    ASSERT_EQ(live.size(), expected.size());
    ASSERT_FALSE(live.empty());
    size_t fewerFrames = 0;
    for (size_t i = 0; i < live.size(); ++i)
    {
        expectSameBearing(*live[i], *expected[i]);
        EXPECT_LE(live[i]->framesUsed, 2u) << i;
        if (i < unlimited.size() && live[i]->framesUsed < unlimited[i]->framesUsed) ++fewerFrames;
    }
    EXPECT_GE(fewerFrames, live.size() / 2);  // without odometry they grow to the window's 8
}

TEST(LiveBearingWorker, AFullQueueSkipsEstimationButDeliversEveryFrameInOrder)
{
    const auto frames = sampleFrames();
    std::promise<void> release;
    auto estimator = std::make_unique<GatedEstimator>(release.get_future().share());
    auto entered = estimator->entered.get_future();
    auto processor = std::make_unique<bearing::BearingProcessor>(
        CsiPreprocessor(
            PreprocessOptions(),
            AntennaArray::fromYamlFile(test::sourceDir() + "/share/arrays/rt-ac86u.yaml")),
        std::move(estimator), bearing::BearingProcessor::Options());
    auto s = settingsFor("gated");
    s.queueLength = 2;
    LiveBearingWorker worker(std::move(processor), s);

    // The first frame is being estimated (blocked), two wait, the rest skip estimation.
    worker.submit(frames[0]);
    ASSERT_EQ(entered.wait_for(std::chrono::seconds(10)), std::future_status::ready);
    const auto t0 = std::chrono::steady_clock::now();
    for (size_t i = 1; i < frames.size(); ++i) worker.submit(frames[i]);
    EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(1));  // never waits
    std::vector<mrpt::obs::CObservation::Ptr> out;
    worker.takeReady(out);
    EXPECT_TRUE(out.empty());  // frame 0 is not done: nothing overtakes it
    auto st = worker.stats();
    EXPECT_EQ(st.submitted, 22u);
    EXPECT_EQ(st.skipped, 19u);

    release.set_value();
    ASSERT_TRUE(worker.waitIdle(30.0));
    worker.takeReady(out);
    st = worker.stats();
    EXPECT_EQ(st.estimated, 3u);
    EXPECT_EQ(st.bearings, 3u);
    std::vector<CObservationWiFiCSI::Ptr> csi;
    size_t bearingsSeen = 0;
    for (const auto& o : out)
        if (auto c = std::dynamic_pointer_cast<CObservationWiFiCSI>(o))
            csi.push_back(c);
        else if (std::dynamic_pointer_cast<CObservationWiFiBearing>(o))
        {
            ++bearingsSeen;
            EXPECT_LE(csi.size(), 3u);  // only the estimated frames have one
        }
    EXPECT_EQ(bearingsSeen, 3u);
    EXPECT_EQ(csi, frames);
}

TEST(LiveBearingWorker, ConfigurationErrorsNameTheKey)
{
    // Off by default; the other bearing keys without an algorithm are a mistake.
    EXPECT_EQ(configError(""), "");
    auto e = configError("bearing_calibration = /nonexistent\n");
    EXPECT_NE(e.find("needs bearing_algorithm"), std::string::npos) << e;

    e = configError("bearing_algorithm = no_such_estimator\n");
    EXPECT_NE(e.find("section 'CSI'"), std::string::npos) << e;
    EXPECT_NE(e.find("key 'bearing_algorithm'"), std::string::npos) << e;
    EXPECT_NE(e.find("no_such_estimator"), std::string::npos) << e;
    // The synthetic aperture needs a peer's recording the live sensor never has.
    e = configError("bearing_algorithm = sar\n");
    EXPECT_NE(e.find("key 'bearing_algorithm'"), std::string::npos) << e;
    EXPECT_NE(e.find("csi-bearings"), std::string::npos) << e;

    e = configError("bearing_algorithm = aoa_only\nbearing_calibration = /nonexistent/calib\n");
    EXPECT_NE(e.find("key 'bearing_calibration'"), std::string::npos) << e;
    e = configError("bearing_algorithm = aoa_only\nbearing_array = /nonexistent.yaml\n");
    EXPECT_NE(e.find("key 'bearing_array'"), std::string::npos) << e;
    e = configError("bearing_algorithm = aoa_only\nbearing_queue_length = 0\n");
    EXPECT_NE(e.find("bearing_queue_length"), std::string::npos) << e;

    test::TempDir tmp;
    std::ofstream(tmp.file("opts.yaml")) << "estimators:\n  fft:\n    no_such_option: 3\n";
    e = configError("bearing_algorithm = fft\nbearing_options = " + tmp.file("opts.yaml") + "\n");
    EXPECT_NE(e.find("key 'bearing_algorithm'"), std::string::npos) << e;
    EXPECT_NE(e.find("no_such_option"), std::string::npos) << e;
    std::ofstream(tmp.file("bad.yaml")) << "preprocess:\n  no_such_step: true\n";
    e = configError("bearing_algorithm = fft\nbearing_options = " + tmp.file("bad.yaml") + "\n");
    EXPECT_NE(e.find("key 'bearing_options'"), std::string::npos) << e;

    e = configError("bearing_algorithm = fft\nbearing_options = {no_such_option: 1}\n");
    EXPECT_NE(e.find("no_such_option"), std::string::npos) << e;
    EXPECT_EQ(configError("bearing_algorithm = fft\nbearing_options = {angle_bins: 90}\n"), "");

    std::ofstream(tmp.file("ok.yaml")) << "window:\n  stride: 2\nestimators:\n  fft:\n"
                                          "    angle_bins: 90\n";
    EXPECT_EQ(
        configError(
            "bearing_algorithm = fft\nbearing_options = " + tmp.file("ok.yaml") +
            "\nbearing_calibration = " + tmp.path().string() + "\n"),
        "");
}

TEST(LiveBearingWorker, CalibrationIsReportedPerChannel)
{
    test::TempDir tmp;
    const std::string dir = tmp.file("calib");
    zeroCalibration("155/80", today())
        .saveYamlFile(PhaseCalibration::pathFor(dir, "rt-ac86u", Chanspec::fromString("155/80")));
    zeroCalibration("42/80", "2020-01-01T00:00:00Z")
        .saveYamlFile(PhaseCalibration::pathFor(dir, "rt-ac86u", Chanspec::fromString("42/80")));
    auto s = settingsFor("aoa_only");
    s.calibration = dir;
    auto p = makeLiveBearingProcessor(s);
    const auto now = mrpt::Clock::now();
    const auto describe = [&](const std::string& cs)
    { return LiveBearingWorker::describeCalibration(*p, Chanspec::fromString(cs), 4, 7, now); };

    // A folder: the file of the channel (auto channel mode moves between them).
    auto m = describe("155/80");
    EXPECT_FALSE(m.problem) << m.text;
    EXPECT_NE(m.text.find("ch155_80mhz.yaml"), std::string::npos) << m.text;
    m = describe("42/80");
    EXPECT_TRUE(m.problem);
    EXPECT_NE(m.text.find("stale"), std::string::npos) << m.text;
    EXPECT_NE(m.text.find("ch42_80mhz.yaml"), std::string::npos) << m.text;
    m = describe("106/80");
    EXPECT_TRUE(m.problem);
    EXPECT_NE(m.text.find("no calibration for 106/80"), std::string::npos) << m.text;
    EXPECT_NE(m.text.find("ch155_80mhz.yaml"), std::string::npos) << m.text;  // what there is
    // ... and what to run for the missing one (a channel schedule visits it).
    EXPECT_NE(m.text.find("run wifi-calibrate"), std::string::npos) << m.text;
    EXPECT_NE(m.text.find("ch106_80mhz.yaml"), std::string::npos) << m.text;

    // One file for another channel, or another device.
    s.calibration = PhaseCalibration::pathFor(dir, "rt-ac86u", Chanspec::fromString("155/80"));
    p = makeLiveBearingProcessor(s);
    m = describe("42/80");
    EXPECT_TRUE(m.problem);
    EXPECT_NE(m.text.find("is for channel 155/80"), std::string::npos) << m.text;
    auto other = zeroCalibration("155/80", today());
    other.device = "another-router";
    other.saveYamlFile(tmp.file("other.yaml"));
    s.calibration = tmp.file("other.yaml");
    p = makeLiveBearingProcessor(s);
    m = describe("155/80");
    EXPECT_TRUE(m.problem);
    EXPECT_NE(m.text.find("another-router"), std::string::npos) << m.text;

    // The worker reports the configured channel at start and every new channel's first frame,
    // and frames a calibration does not fit get no bearing (counted), without stopping.
    LiveBearingWorker worker(std::move(p), s, Chanspec::fromString("155/80"));
    auto msgs = worker.takeMessages();
    ASSERT_EQ(msgs.size(), 1u);
    EXPECT_TRUE(msgs[0].problem);
    for (const auto& f : sampleFrames()) worker.submit(f);
    ASSERT_TRUE(worker.waitIdle(30.0));
    msgs = worker.takeMessages();
    ASSERT_EQ(msgs.size(), 1u);
    EXPECT_NE(msgs[0].text.find("first frame on 155/80"), std::string::npos) << msgs[0].text;
    EXPECT_EQ(worker.stats().calibrationErrors, 22u);
    EXPECT_EQ(worker.stats().bearings, 0u);
}
