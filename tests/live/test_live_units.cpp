/* mrpt_wifi — the emulator's odometry stream, CWiFiOdometryUdpSensor, the unknown-motion
 * model of the live filter. */
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/emulator/Emulator.h>
#include <mrpt_wifi/emulator/LoopbackUdp.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>
#include <mrpt_wifi/sensor/CWiFiOdometryUdpSensor.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <thread>

#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
bool parse(const std::string& text, mrpt::obs::CObservationOdometry& o, uint64_t& seq)
{
    return CWiFiOdometryUdpSensor::parseDatagram(
        reinterpret_cast<const uint8_t*>(text.data()), text.size(), o, seq);
}

/** A sensor on a free loopback port (udp_port = 0). */
std::unique_ptr<CWiFiOdometryUdpSensor> makeSensor()
{
    mrpt::config::CConfigFileMemory ini(
        "[ODO]\ndriver = CWiFiOdometryUdpSensor\nsensorLabel = ODO\nudp_port = 0\n");
    auto s = std::make_unique<CWiFiOdometryUdpSensor>();
    s->loadConfig(ini, "ODO");
    s->initialize();
    return s;
}

std::vector<mrpt::obs::CObservationOdometry::Ptr> collect(CWiFiOdometryUdpSensor& s)
{
    s.doProcess();
    mrpt::hwdrivers::CGenericSensor::TListObservations l;
    s.getObservations(l);
    std::vector<mrpt::obs::CObservationOdometry::Ptr> out;
    for (const auto& [t, o] : l)
        out.push_back(std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o));
    return out;
}

const std::string kLocalizationShare = MRPT_WIFI_SOURCE_DIR "/share/localization";

/** wifi-localize-emulator.ini with its AP map found from anywhere. */
mrpt::config::CConfigFileMemory emulatorLocalizationIni()
{
    mrpt::config::CConfigFileMemory ini(
        mrpt::io::file_get_contents(kLocalizationShare + "/wifi-localize-emulator.ini"));
    ini.write(
        "MetricMap_wifiBearingMap_00_creationOpts", "transmitters_file",
        kLocalizationShare + "/kidnapped-aps.yaml");
    return ini;
}
}  // namespace

TEST(OdometryDatagram, RoundTripsThroughTheSensorParser)
{
    const auto d = emulator::odometryDatagram(
        41, 12.25, mrpt::math::TPose2D(1.5, -2.25, 0.75), mrpt::math::TTwist2D(0.6, 0.0, -0.3));
    mrpt::obs::CObservationOdometry o;
    uint64_t seq = 0;
    ASSERT_TRUE(parse(d, o, seq)) << d;
    EXPECT_EQ(seq, 41u);
    EXPECT_NEAR(o.odometry.x(), 1.5, 1e-9);
    EXPECT_NEAR(o.odometry.y(), -2.25, 1e-9);
    EXPECT_NEAR(o.odometry.phi(), 0.75, 1e-7);
    ASSERT_TRUE(o.hasVelocities);
    EXPECT_NEAR(o.velocityLocal.vx, 0.6, 1e-9);
    EXPECT_NEAR(o.velocityLocal.omega, -0.3, 1e-7);
}

TEST(OdometryDatagram, MalformedDatagramsAreRejected)
{
    mrpt::obs::CObservationOdometry o;
    uint64_t seq = 0;
    EXPECT_FALSE(parse("", o, seq));
    EXPECT_FALSE(parse("hello", o, seq));
    EXPECT_FALSE(parse("MRPT_WIFI_ODO 2 1 0 0 0 0 0 0 0\n", o, seq));       // version
    EXPECT_FALSE(parse("MRPT_WIFI_ODO 1 1 0 0 0 0 0 0\n", o, seq));         // one short
    EXPECT_FALSE(parse("MRPT_WIFI_ODO 1 1 0 0 0 0 0 0 0 junk\n", o, seq));  // trailing
    EXPECT_FALSE(parse("MRPT_WIFI_ODO 1 1 0 nan 0 0 0 0 0\n", o, seq));     // not finite
    EXPECT_TRUE(parse("MRPT_WIFI_ODO 1 1 0 0 0 0 0 0 0\n", o, seq));
}

TEST(OdometrySensor, EmitsObservationsCountsGapsAndIgnoresGarbage)
{
    auto s = makeSensor();
    ASSERT_NE(s->boundPort(), 0);
    emulator::LoopbackUdpSender tx(emulator::loopbackDestination("127.0.0.1", s->boundPort()));
    for (uint64_t seq : {0, 1, 2, 5})
    {
        const auto d = emulator::odometryDatagram(
            seq, 0.05 * double(seq), mrpt::math::TPose2D(0.1 * double(seq), 0, 0), {});
        ASSERT_TRUE(tx.send(reinterpret_cast<const uint8_t*>(d.data()), d.size()));
    }
    const std::string junk = "not odometry";
    tx.send(reinterpret_cast<const uint8_t*>(junk.data()), junk.size());
    std::vector<mrpt::obs::CObservationOdometry::Ptr> got;
    for (int i = 0; i < 100 && got.size() < 4; ++i)
    {
        for (auto& o : collect(*s)) got.push_back(o);
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_EQ(got.size(), 4u);
    EXPECT_EQ(got.back()->sensorLabel, "ODO");
    EXPECT_NEAR(got.back()->odometry.x(), 0.5, 1e-9);
    EXPECT_NE(got.back()->timestamp, INVALID_TIMESTAMP);
    EXPECT_EQ(s->lost(), 2u);  // 3 and 4
    for (int i = 0; i < 20 && s->malformed() == 0; ++i)
    {
        collect(*s);
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    EXPECT_EQ(s->malformed(), 1u);
}

TEST(OdometrySensor, BadPortIsAnErrorNamingTheSection)
{
    mrpt::config::CConfigFileMemory ini("[ODO]\nudp_port = 70000\n");
    CWiFiOdometryUdpSensor s;
    try
    {
        s.loadConfig(ini, "ODO");
        FAIL() << "no error";
    }
    catch (const std::exception& e)
    {
        const std::string m = e.what();
        EXPECT_NE(m.find("section 'ODO', udp_port = 70000"), std::string::npos) << m;
    }
}

TEST(EmulatorOdometry, StreamsTheScenarioOdometryLive)
{
    auto s = makeSensor();
    emulator::EmulatorOptions o;
    o.scenario = sim::Scenario::fromYamlFile(test::sourceDir() + "/share/scenarios/kidnapped.yaml");
    o.port = uint16_t(s->boundPort() == 5999 ? 5998 : 5999);  // CSI: nobody listens (loopback)
    o.odometryPort = s->boundPort();
    o.duration_s = 1.0;
    emulator::Emulator emu(o);
    std::thread th([&] { emu.run(); });
    std::vector<mrpt::obs::CObservationOdometry::Ptr> got;
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (std::chrono::steady_clock::now() < until)
    {
        for (auto& x : collect(*s)) got.push_back(x);
        if (got.size() >= 15) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    th.join();
    for (auto& x : collect(*s)) got.push_back(x);
    // 20 Hz over 1 s of wall clock, sent as it happens: the first samples of the scenario, every
    // one the emulator says it sent (how many depends on the machine's load, never above 21).
    ASSERT_GT(got.size(), 0u);
    EXPECT_LE(got.size(), 21u);
    EXPECT_EQ(emu.counters().odometrySent, got.size() + s->lost());
    sim::Simulator sim(*o.scenario);
    for (size_t i = 0; i < got.size(); ++i)
    {
        const auto& ref = sim.odometry()[i].odometry;
        EXPECT_NEAR(got[i]->odometry.x(), ref.x, 1e-5) << i;
        EXPECT_NEAR(got[i]->odometry.y(), ref.y, 1e-5) << i;
    }
    // Arrival times follow the 20 Hz schedule (not all at once).
    const double span = mrpt::Clock::toDouble(got.back()->timestamp) -
                        mrpt::Clock::toDouble(got.front()->timestamp);
    EXPECT_GT(span, 0.5);
}

TEST(EmulatorOdometry, ReplayHasNoOdometryToStream)
{
    emulator::EmulatorOptions o;
    o.replayFile = test::sourceDir() + "/share/samples/sample_4x4_80mhz.pcap";
    o.odometryPort = 5999;
    EXPECT_THROW(emulator::Emulator{o}, std::invalid_argument);
}

TEST(UnknownMotion, RandomWalkSpreadIsIndependentOfTheStepRate)
{
    // The zero-mean walk with a 1 s horizon: after one second, the speed bound.
    localization::UnknownMotion m;
    m.maxSpeed_mps = 1.0, m.maxTurnRate_dps = 90, m.correlationTime_s = 1.0, m.maxStep_s = 5;
    m.minStdXY_m = m.minStdPhi_deg = 1e-9;
    m.constantVelocity = false;
    const auto a = m.makeAction(0.5);
    const auto& pdf = *a->poseChange;
    mrpt::poses::CPose2D mean;
    pdf.getMean(mean);
    EXPECT_NEAR(mean.norm(), 0.0, 1e-12);
    const auto cov = pdf.getCovariance();
    EXPECT_NEAR(std::sqrt(cov(0, 0)), std::sqrt(0.5), 0.05);
    EXPECT_NEAR(std::sqrt(cov(2, 2)), mrpt::DEG2RAD(90.0) * std::sqrt(0.5), 0.05);
    // Ten steps of 0.05 s spread as much as one of 0.5 s (variance linear in time).
    const auto b = m.makeAction(0.05);
    EXPECT_NEAR(10 * b->poseChange->getCovariance()(0, 0), cov(0, 0), 0.02 * cov(0, 0));
}

TEST(LiveLocalizer, TempersTheBearingsByTheMotionModelInUse)
{
    // Without odometry [UnknownMotion]'s bearing_weight applies, from the first odometry
    // reading on [OdometryMotion]'s instead; both on top of the map's own.
    auto ini = emulatorLocalizationIni();
    ini.write("MetricMap_wifiBearingMap_00_likelihoodOpts", "bearing_weight", 0.8);
    ini.write("UnknownMotion", "bearing_weight", 0.5);
    ini.write("OdometryMotion", "bearing_weight", 0.3);
    localization::LiveLocalizer loc(ini, kLocalizationShare);
    EXPECT_DOUBLE_EQ(loc.wifiMap().likelihoodOptions.bearingWeight, 0.8 * 0.5);
    mrpt::obs::CObservationOdometry odo;
    loc.addOdometry(odo);
    EXPECT_DOUBLE_EQ(loc.wifiMap().likelihoodOptions.bearingWeight, 0.8 * 0.3);
    odo.odometry = mrpt::poses::CPose2D(0.1, 0, 0);
    loc.addOdometry(odo);  // applied once, not once per reading
    EXPECT_DOUBLE_EQ(loc.wifiMap().likelihoodOptions.bearingWeight, 0.8 * 0.3);
}

TEST(LiveLocalizer, StepsTakeTheCapAndCatchUpWithWhatIsQueuedTooLong)
{
    // max_bearings_per_step bounds a step; what is more than max_queue_s older than the newest
    // bearing, or than the clock's now, goes into the next step beyond it: a late filter
    // catches up.
    auto ini = emulatorLocalizationIni();
    ini.write("wifi-localize", "max_bearings_per_step", 2);
    ini.write("wifi-localize", "max_queue_s", 0.51);
    ini.write("LocalizationExperiment", "particles_count", 200);
    localization::LiveLocalizer loc(ini, kLocalizationShare);
    const auto& ap = loc.wifiMap().transmitters().transmitters().at(0);
    const auto bearingAt = [&](double t)
    {
        auto b = CObservationWiFiBearing::Create();
        b->timestamp = mrpt::Clock::fromDouble(1.7e9 + t);
        b->transmitter = ap.mac;
        b->aoa_rad = 0.3;
        b->aoaStd_rad = mrpt::DEG2RAD(3.0);
        return b;
    };
    // 100 bearings 0.02 s apart, queued in reverse order: t = 0 ... 1.98 s.
    for (int i = 99; i >= 0; --i) loc.addBearing(bearingAt(0.02 * i));
    ASSERT_TRUE(loc.step());
    // Older than 1.98 - 0.51 s: t = 0 ... 1.46 s, 74 bearings, in one step, oldest first.
    EXPECT_EQ(loc.bearingsUsed(), 74u);
    EXPECT_NEAR(loc.lastStepTime(), 1.7e9 + 1.46, 1e-5);
    size_t steps = 1;
    while (loc.step()) ++steps;
    EXPECT_EQ(steps, 1u + 13u);  // the other 26 two at a time
    EXPECT_EQ(loc.bearingsUsed(), 100u);
    EXPECT_NEAR(loc.lastStepTime(), 1.7e9 + 1.98, 1e-5);

    // A queue that spans less than max_queue_s: two per step.
    for (int i = 0; i < 5; ++i) loc.addBearing(bearingAt(2.0 + 0.02 * i));
    ASSERT_TRUE(loc.step());
    EXPECT_EQ(loc.bearingsUsed(), 102u);
    // Unless the clock says they are all late (the CSI before them was): all in one step.
    ASSERT_TRUE(loc.step(1.7e9 + 2.5));
    EXPECT_EQ(loc.bearingsUsed(), 104u);  // 2.04 and 2.06 s: not older than 2.5 - 0.51 s
    for (int i = 0; i < 5; ++i) loc.addBearing(bearingAt(2.1 + 0.02 * i));
    ASSERT_TRUE(loc.step(1.7e9 + 3.0));
    EXPECT_EQ(loc.bearingsUsed(), 110u);
    EXPECT_FALSE(loc.step(1.7e9 + 3.0));

    ini.write("wifi-localize", "max_queue_s", -1.0);
    EXPECT_THROW(localization::LiveLocalizer(ini, kLocalizationShare), std::invalid_argument);
}

TEST(LiveLocalizer, OnceTheSmootherStopsItsLastOffsetStaysInTheSigma)
{
    // With odometry the smoother's estimate is reported while its solves are used; when they
    // stop, the particles' mean is, and how far it was last seen from the smoother's estimate
    // stays in the reported σ: a narrow cloud can lag the robot by more than its own spread.
    auto ini = emulatorLocalizationIni();
    ini.write("MetricMap_wifiBearingMap_00_likelihoodOpts", "use_aoa", true);
    ini.write("MetricMap_wifiBearingMap_00_likelihoodOpts", "use_aod", false);
    ini.write("wifi-localize", "bearing_bias_std_deg", 0.0);  // the particles' σ alone
    for (const auto& [section, key] :
         {std::pair{"LocalizationExperiment", "particles_count"},
          {"KLD_options", "KLD_minSampleSize"},
          {"KLD_options", "KLD_maxSampleSize"}})
        ini.write(section, key, 500);
    mrpt::random::getRandomGenerator().randomize(3);
    localization::LiveLocalizer loc(ini, kLocalizationShare);
    const auto& aps = loc.wifiMap().transmitters().transmitters();
    ASSERT_GE(aps.size(), 3u);

    // A circle of 1.5 m radius in the 10 x 5 m room at 0.375 m/s, odometry 10 % short; every
    // 0.1 s one AoA per AP, 2° of noise, reported with σ 3°. From 20 s every AoA is 90° off.
    const auto poseAt = [](double t, double radius = 1.5)
    {
        const double a = 0.25 * t;
        return mrpt::math::TPose2D(5 + radius * std::sin(a), 2.5 - radius * std::cos(a), a);
    };
    const double t0 = 1.7e9, kBad_s = 20;
    std::optional<mrpt::math::TPose2D> lastOffset;
    bool withdrawn = false;
    for (int i = 0; i <= 260 && !withdrawn; ++i)
    {
        const double t = 0.1 * i;
        const auto truth = poseAt(t);
        mrpt::obs::CObservationOdometry odo;
        odo.timestamp = mrpt::Clock::fromDouble(t0 + t);
        odo.odometry = mrpt::poses::CPose2D(poseAt(t, 1.35));  // 10 % short
        loc.addOdometry(odo);
        for (const auto& ap : aps)
        {
            auto b = CObservationWiFiBearing::Create();
            b->timestamp = odo.timestamp;
            b->transmitter = ap.mac;
            b->aoa_rad = mrpt::math::wrapToPi(
                localization::predictAoa(truth, ap.pose.x, ap.pose.y) +
                mrpt::random::getRandomGenerator().drawGaussian1D(0, mrpt::DEG2RAD(2.0)) +
                (t >= kBad_s ? M_PI / 2 : 0.0));
            b->aoaStd_rad = mrpt::DEG2RAD(3.0);
            loc.addBearing(b);
        }
        ASSERT_TRUE(loc.step());
        while (loc.step())  // the queue drained, as wifi-localize drains it
            ;
        const auto mean = loc.mean(), estimate = loc.estimate();
        if (estimate.x != mean.x || estimate.y != mean.y)
        {
            ASSERT_LT(t, kBad_s + 1) << "the smoother explained bearings 90° off";
            lastOffset.emplace(estimate.x - mean.x, estimate.y - mean.y, 0.0);
        }
        else
            withdrawn = lastOffset && t >= kBad_s;
    }
    ASSERT_TRUE(lastOffset) << "the smoother never gave an estimate";
    ASSERT_TRUE(withdrawn) << "the smoother still gives an estimate on bearings 90° off";
    const double distance2 = lastOffset->x * lastOffset->x + lastOffset->y * lastOffset->y;
    ASSERT_GT(distance2, 0.0);
    const auto u = loc.uncertainty();
    EXPECT_NEAR(u.reported(0, 0), u.particles(0, 0) + distance2, 1e-9 + 1e-6 * distance2);
    EXPECT_NEAR(u.reported(1, 1), u.particles(1, 1) + distance2, 1e-9 + 1e-6 * distance2);
    EXPECT_DOUBLE_EQ(u.reported(0, 1), u.particles(0, 1));
}

TEST(LiveLagRecord, PercentilesOfEveryLagInMemoryBoundedByTheirRange)
{
    // wifi-localize's lag summary over a long run: the same p50 / p99 / max as all the lags
    // kept and sorted (at the 0.1 ms it prints), while what is kept follows the lags' range
    // (here 0..0.4 s: at most 4001 values of 0.1 ms), not their number.
    localization::LagRecord record;
    EXPECT_TRUE(std::isnan(record.percentile(0.5)));
    std::vector<double> all;
    std::mt19937 rng(56);
    std::exponential_distribution<double> tail(1 / 0.01);
    for (int i = 0; i < 300000; ++i)
    {
        const double lag = std::min(0.4, 0.003 + tail(rng));
        all.push_back(lag);
        record.add(lag);
    }
    EXPECT_EQ(record.count(), all.size());
    EXPECT_LE(record.bins(), 4001u);
    std::sort(all.begin(), all.end());
    const auto printed = [](double s)
    {
        char b[32];
        std::snprintf(b, sizeof(b), "%.1f", s * 1e3);
        return std::string(b);
    };
    for (const double q : {0.0, 0.5, 0.9, 0.99, 1.0})
    {
        const size_t rank = std::min(all.size() - 1, size_t(q * double(all.size())));
        EXPECT_EQ(printed(record.percentile(q)), printed(all[rank])) << "q = " << q;
    }
}

TEST(LiveDeviceMapper, OffUnlessAskedAndBadOptionsNameTheKey)
{
    mrpt::config::CConfigFileMemory none("[wifi-localize]\n");
    EXPECT_FALSE(localization::LiveDeviceMapper(none, "wifi-localize").enabled());
    mrpt::config::CConfigFileMemory bad("[wifi-localize]\nmap_devices = true\nmap_loss = cauchi\n");
    try
    {
        localization::LiveDeviceMapper m(bad, "wifi-localize");
        FAIL() << "accepted map_loss = cauchi";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("map_loss"), std::string::npos) << e.what();
    }
}

TEST(LiveDeviceMapper, FindsADeviceFromBearingsAlongTheOdometryInAnyArrivalOrder)
{
    mrpt::config::CConfigFileMemory ini("[wifi-localize]\nmap_devices = true\n");
    localization::LiveDeviceMapper m(ini, "wifi-localize");
    ASSERT_TRUE(m.enabled());
    const double devX = 3.0, devY = 2.0;
    const auto mac = MacAddress::fromString("02:00:00:00:03:09");
    // The robot drives along y = 0 from x = 0 to 6 m (yaw 0); the odometry arrives after all
    // bearings and newest first (sensor threads deliver in their own order).
    std::vector<mrpt::obs::CObservationOdometry> odo;
    for (int i = 0; i <= 60; ++i)
    {
        const double t = 1000.0 + 0.1 * i, x = 0.1 * i;
        auto b = CObservationWiFiBearing::Create();
        b->timestamp = mrpt::Clock::fromDouble(t);
        b->transmitter = mac;
        b->aoa_rad = std::atan2(devY, devX - x);
        b->aoaStd_rad = mrpt::DEG2RAD(3.0);
        m.addBearing(*b);
        mrpt::obs::CObservationOdometry o;
        o.timestamp = mrpt::Clock::fromDouble(t);
        o.odometry = mrpt::poses::CPose2D(x, 0, 0);
        odo.push_back(o);
    }
    for (auto it = odo.rbegin(); it != odo.rend(); ++it) m.addOdometry(*it);
    m.update();
    ASSERT_EQ(m.devices().size(), 1u);
    const auto& d = m.devices()[0];
    EXPECT_EQ(d.mac, mac);
    EXPECT_TRUE(d.localized) << d.note;
    EXPECT_NEAR(d.x, devX, 0.05);
    EXPECT_NEAR(d.y, devY, 0.05);
    EXPECT_EQ(m.bearings(), 61u);
}
