/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * The transmit side: the simulator's per-chain AP phases recovered by the receiver's method
 * mirrored at the AP (true and odometry poses), AoD gated off without such a calibration, the
 * version-2 calibration file (and version-1 files still loading). */
#include <gtest/gtest.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/calib/CalibrationCheck.h>
#include <mrpt_wifi/calib/PoseTrack.h>
#include <mrpt_wifi/obs/bearing/BearingProcessor.h>

#include "CalibTestSupport.h"
#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::calib;

namespace
{
constexpr double kDeg = M_PI / 180;

/** Two 4-stream APs in a 10 x 5 m room (walls |Γ| = 0.45, a pillar), a random walk with
 *  drifting odometry, 25 dB; every transmit impairment at its default (on). */
std::string scenarioText(double duration_s, uint32_t seed)
{
    const std::string arrays = std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/";
    std::ostringstream s;
    s << "name: txcalib\nduration_s: " << duration_s << "\nseed: " << seed << "\n"
      << "room:\n  corners: [[0, 0], [10, 0], [10, 5], [0, 5]]\n"
         "  reflection: {magnitude: 0.45, phase_deg: 180}\n"
         "scatterers:\n  - {name: pillar, position: [6.5, 1.5], rcs_m2: 0.5}\n"
         "transmitters:\n"
         "  - {name: ap-nw, mac: '02:00:00:00:01:01', position: [0.3, 4.7], yaw_deg: -45,"
         " channel: 155/80, streams: 4, array: "
      << arrays
      << "ap-linear-4.yaml}\n"
         "  - {name: ap-se, mac: '02:00:00:00:01:03', position: [9.7, 0.3], yaw_deg: 135,"
         " channel: 155/80, streams: 4, array: "
      << arrays << "ap-linear-4.yaml}\n"
      << "receiver:\n  array: " << arrays
      << "rt-ac86u.yaml\n  sensor_pose: {x: 0.1, y: 0.0, z: 0.4, yaw_deg: 0}\n"
         "motion:\n  type: random_walk\n  start: [5.0, 2.5, 0]\n  center: [5.0, 2.5]\n"
         "  radius_m: 6.0\n  speed_mps: 0.6\n  turn_rate_dps: 90\n"
         "odometry:\n  rate_hz: 20\n  sigma_xy_m_per_sqrt_m: 0.02\n"
         "  sigma_yaw_deg_per_sqrt_m: 1.0\n"
         "impairments:\n  snr_db: 25\n";
    return s.str();
}

sim::Scenario scenario(double duration_s, uint32_t seed)
{
    return sim::Scenario::fromYamlText(scenarioText(duration_s, seed), "txcalib", ".");
}

AntennaArray apArray()
{
    return AntennaArray::fromYamlFile(
        std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/ap-linear-4.yaml");
}

/** Receiver and both APs calibrated from the first `until_s` seconds of the drive, with the
 *  true poses or the drifting odometry placed at the (known) start pose. */
struct DriveCalibration
{
    ChannelCalibration receiver;
    std::map<MacAddress, ChannelCalibration> transmitters;
};

DriveCalibration calibrateDrive(sim::Simulator& sim, double until_s, bool odometryPoses)
{
    const auto& sc = sim.scenario();
    PoseTrack odo;
    for (const auto& s : sim.odometry()) odo.add(s.time_s, s.odometry);
    odo = odo.transformed(sc.motion.start);

    FramePreparer prep(calibtest::rtac86u());
    PhaseCalibrator rx(calibtest::rtac86u());
    std::map<MacAddress, PhaseCalibrator> tx;
    for (const auto& t : sc.transmitters) tx.emplace(t.mac, PhaseCalibrator(apArray()));
    TransmitChainFramer framer;
    CalibrationFrame f, ft;
    sim.setOdometryEnabled(false);
    sim.rewind(0);
    sim::SimEvent ev;
    while (sim.next(ev) && ev.time_s < until_s)
    {
        if (ev.kind != sim::SimEvent::Kind::Csi) continue;
        const auto& t = sc.transmitters.at(ev.frame.transmitterIndex);
        mrpt::math::TPose2D robot = ev.frame.robotPose;
        if (odometryPoses && !odo.at(ev.time_s, robot)) continue;
        if (prep.prepare(*ev.csi, robot, {t.pose.x, t.pose.y}, f) != RejectReason::Accepted)
            continue;
        rx.add(f);
        if (framer.make(f, t.pose, 4, ft)) tx.at(t.mac).add(ft);
    }
    DriveCalibration out;
    out.receiver = rx.solve(rx.channels().at(0));
    for (auto& [mac, c] : tx)
    {
        out.transmitters[mac] = c.solve(c.channels().at(0));
        auto& cal = out.transmitters[mac].calibration;
        cal.role = PhaseCalibration::Role::Transmitter;
        cal.transmitter = mac;
        cal.aodResidual_rad =
            1.4826 * quantile(out.transmitters[mac].bearingErrorAfter_deg, 0.5) * kDeg;
    }
    return out;
}

/** RMS [deg] of the recovered transmit-chain phases against the simulator's (relative to
 *  chain 0), over chains 1.. and all subcarriers. */
double txPhaseErrorRms_deg(const PhaseCalibration& c, const sim::TransmitterHardware& hw)
{
    double acc = 0;
    size_t n = 0;
    for (size_t m = 1; m < c.antennas(); ++m)
    {
        const double truth = hw.chain(c.chanspec, unsigned(m)).phaseOffset_rad -
                             hw.chain(c.chanspec, 0).phaseOffset_rad;
        for (double p : c.phases_rad[m])
        {
            const double e = wrapAngle(p - truth);
            acc += e * e;
            ++n;
        }
    }
    return std::sqrt(acc / double(n)) / kDeg;
}

/** The uncalibrated phases' error, for scale: what the offsets themselves are. */
double txOffsetRms_deg(const Chanspec& cs, const sim::TransmitterHardware& hw)
{
    double acc = 0;
    for (unsigned m = 1; m < hw.streams(); ++m)
    {
        const double e =
            wrapAngle(hw.chain(cs, m).phaseOffset_rad - hw.chain(cs, 0).phaseOffset_rad);
        acc += e * e;
    }
    return std::sqrt(acc / (hw.streams() - 1)) / kDeg;
}

class TxChainCalibration : public ::testing::Test
{
protected:
    static void SetUpTestSuite()
    {
        sim_ = std::make_unique<sim::Simulator>(scenario(60, 2024));
        truePoses_ = calibrateDrive(*sim_, 30, false);
        odometryPoses_ = calibrateDrive(*sim_, 30, true);
    }
    static void TearDownTestSuite() { sim_.reset(); }
    static std::unique_ptr<sim::Simulator> sim_;
    static DriveCalibration truePoses_, odometryPoses_;
};
std::unique_ptr<sim::Simulator> TxChainCalibration::sim_;
DriveCalibration TxChainCalibration::truePoses_, TxChainCalibration::odometryPoses_;

/** AoD errors [deg] and their σ-normalised values from a BearingProcessor over the frames of
 *  [from_s, to_s) (every 5th frame per AP estimated). */
struct AodRun
{
    size_t bearings = 0, withAod = 0;
    std::vector<double> errors_deg, z;
    double minStd_rad = 1e9;
};

AodRun runAod(
    sim::Simulator& sim, CalibrationStore store, bool uncalibratedAod, double from_s, double to_s)
{
    bearing::BearingProcessor::Options o;
    o.stride = 5;
    o.uncalibratedAod = uncalibratedAod;
    bearing::BearingProcessor proc(
        CsiPreprocessor(PreprocessOptions(), calibtest::rtac86u(), std::move(store)),
        bearing::createEstimator("aod", mrpt::containers::yaml::Map()), o);
    proc.setDefaultTransmitterArray(apArray());
    AodRun r;
    sim.setOdometryEnabled(false);
    sim.rewind(from_s);
    sim::SimEvent ev;
    while (sim.next(ev) && ev.time_s < to_s)
    {
        if (ev.kind != sim::SimEvent::Kind::Csi) continue;
        const auto b = proc.process(*ev.csi);
        if (!b) continue;
        ++r.bearings;
        if (!b->hasAod) continue;
        ++r.withAod;
        const double e = std::abs(wrapAngle(b->aod_rad - ev.frame.aod_rad));
        r.errors_deg.push_back(e / kDeg);
        r.z.push_back(e / b->aodStd_rad);
        r.minStd_rad = std::min(r.minStd_rad, b->aodStd_rad);
    }
    return r;
}

double shareAtMost(const std::vector<double>& v, double limit)
{
    return double(std::count_if(v.begin(), v.end(), [&](double x) { return x <= limit; })) /
           double(std::max<size_t>(v.size(), 1));
}
}  // namespace

TEST_F(TxChainCalibration, RecoversInjectedOffsetsFromTruePoses)
{
    for (size_t i = 0; i < sim_->scenario().transmitters.size(); ++i)
    {
        const auto& t = sim_->scenario().transmitters[i];
        const auto& res = truePoses_.transmitters.at(t.mac);
        const auto& hw = sim_->transmitterHardware(i);
        const double err = txPhaseErrorRms_deg(res.calibration, hw);
        std::cout << t.name << ": injected offsets " << txOffsetRms_deg(t.chanspec, hw)
                  << " deg RMS, recovered within " << err << " deg RMS; AoD on the drive median "
                  << quantile(res.bearingErrorBefore_deg, 0.5) << " -> "
                  << quantile(res.bearingErrorAfter_deg, 0.5) << " deg\n";
        EXPECT_LT(err, 15.0) << t.name;
        EXPECT_LT(quantile(res.bearingErrorAfter_deg, 0.5), 4.0) << t.name;
        EXPECT_GT(
            quantile(res.bearingErrorBefore_deg, 0.5), 2 * quantile(res.bearingErrorAfter_deg, 0.5))
            << t.name;
        EXPECT_EQ(res.calibration.antennas(), 4u);
    }
}

TEST_F(TxChainCalibration, ReceiverFromDriftingOdometryWithin3Degrees)
{
    const double withTruth =
        calibtest::phaseErrorRms_deg(truePoses_.receiver.calibration, sim_->hardware());
    const double withOdometry =
        calibtest::phaseErrorRms_deg(odometryPoses_.receiver.calibration, sim_->hardware());
    std::cout << "receiver offsets: " << withTruth << " deg RMS (true poses), " << withOdometry
              << " deg RMS (odometry poses)\n";
    EXPECT_LT(withTruth, 3.0);
    EXPECT_LT(withOdometry, 3.0);
    for (const auto& [mac, res] : odometryPoses_.transmitters)
        EXPECT_LT(quantile(res.bearingErrorAfter_deg, 0.5), 6.0) << mac.asString();
}

TEST_F(TxChainCalibration, AodOnlyWhereCalibratedAndHonestSigma)
{
    // Uncalibrated: the estimator finds an angle, the processor withholds it ...
    const AodRun gated = runAod(*sim_, {}, false, 30, 45);
    EXPECT_GT(gated.bearings, 200u);
    EXPECT_EQ(gated.withAod, 0u);
    // ... unless asked for, and then it is wrong (the offsets are tens of degrees of AoD).
    const AodRun raw = runAod(*sim_, {}, true, 30, 45);
    EXPECT_EQ(raw.withAod, raw.bearings);
    EXPECT_GT(quantile(raw.errors_deg, 0.5), 5.0);

    // Calibrated on the first half (a folder, as wifi-calibrate writes it), AoD on the second.
    const test::TempDir tmp;  // removed with everything in it
    const std::string dir = tmp.file("txcal");
    for (const auto& [mac, res] : truePoses_.transmitters)
        res.calibration.saveYamlFile(
            PhaseCalibration::transmitterPathFor(dir, mac, res.calibration.chanspec));
    const AodRun cal = runAod(*sim_, CalibrationStore::open(dir), false, 30, 60);
    EXPECT_EQ(cal.withAod, cal.bearings);
    const double median = quantile(cal.errors_deg, 0.5);
    const double beyond30 = 1 - shareAtMost(cal.errors_deg, 30);
    const double within3 = shareAtMost(cal.z, 3);
    std::cout << "AoD on the other half: median " << median << " deg, p90 "
              << quantile(cal.errors_deg, 0.9) << " deg, " << 100 * beyond30 << " % beyond 30 deg, "
              << 100 * within3 << " % within 3 sigma (uncalibrated median "
              << quantile(raw.errors_deg, 0.5) << " deg)\n";
    EXPECT_LT(median, 3.0);
    EXPECT_LT(beyond30, 0.05);
    EXPECT_GT(within3, 0.95);
    double residual = 1e9;
    for (const auto& [mac, res] : truePoses_.transmitters)
        residual = std::min(residual, res.calibration.aodResidual_rad);
    EXPECT_GE(cal.minStd_rad, residual);  // the calibration's own error is in every σ
}

TEST(TxCalibrationFile, RoundTripAndOldFormat)
{
    PhaseCalibration c;
    c.device = "ap-linear-4";
    c.chanspec = Chanspec::fromString("155/80");
    c.role = PhaseCalibration::Role::Transmitter;
    c.transmitter = MacAddress::fromString("02:00:00:00:01:01");
    c.aodResidual_rad = 0.031;
    c.subcarriers = {-2, 3, 7};
    c.phases_rad = {{0, 0, 0}, {0.5, 0.6, 0.7}, {-1, -1.1, -1.2}, {2, 2.1, 2.2}};
    c.gains_dB = {0, 0.3, -0.2, 0.1};
    const PhaseCalibration back = PhaseCalibration::fromYamlText(c.asYamlText());
    EXPECT_EQ(back.role, PhaseCalibration::Role::Transmitter);
    EXPECT_EQ(back.transmitter, c.transmitter);
    EXPECT_DOUBLE_EQ(back.aodResidual_rad, 0.031);
    EXPECT_EQ(back.phases_rad, c.phases_rad);
    EXPECT_EQ(back.gains_dB, c.gains_dB);

    // A version-1 file (as every earlier wifi-calibrate wrote) is a receiver calibration.
    const std::string v1 =
        "format: mrpt_wifi_phase_calibration\nversion: 1\ndevice: rt-ac86u\nchanspec: 155/80\n"
        "antennas: 2\nsubcarriers: [-1, 1]\nphases_rad:\n  - [0, 0]\n  - [0.1, 0.2]\n";
    const PhaseCalibration old = PhaseCalibration::fromYamlText(v1);
    EXPECT_EQ(old.role, PhaseCalibration::Role::Receiver);
    EXPECT_NEAR(old.phaseAt(1, 1), 0.2, 1e-12);
    EXPECT_THROW(
        PhaseCalibration::fromYamlText(
            v1 + "role: transmitter\ntransmitter: '02:00:00:00:01:01'\n"),
        CalibrationError);  // version 2 keys in a version 1 file
    std::string v2 = v1;
    v2.replace(v2.find("version: 1"), 10, "version: 2");
    EXPECT_THROW(PhaseCalibration::fromYamlText(v2 + "role: transmitter\n"), CalibrationError);
    EXPECT_THROW(PhaseCalibration::fromYamlText(v2 + "role: relay\n"), CalibrationError);
    EXPECT_THROW(
        PhaseCalibration::fromYamlText(v2 + "transmitter: '02:00:00:00:01:01'\n"),
        CalibrationError);  // a receiver file has no transmitter

    // The folder layout: found for its MAC and channel only; a receiver lookup never takes it.
    const test::TempDir tmp;
    const std::string dir = tmp.file("txfile");
    c.saveYamlFile(PhaseCalibration::transmitterPathFor(dir, c.transmitter, c.chanspec));
    const auto store = CalibrationStore::open(dir);
    ASSERT_NE(store.findTransmitter(c.transmitter, c.chanspec, 4), nullptr);
    EXPECT_EQ(
        store.findTransmitter(MacAddress::fromString("02:00:00:00:01:09"), c.chanspec, 4), nullptr);
    EXPECT_EQ(store.findTransmitter(c.transmitter, Chanspec::fromString("42/80"), 4), nullptr);
    EXPECT_THROW(store.findTransmitter(c.transmitter, c.chanspec, 5), CalibrationError);
    const auto single = CalibrationStore::open(
        PhaseCalibration::transmitterPathFor(dir, c.transmitter, c.chanspec));
    EXPECT_THROW(single.find("ap-linear-4", c.chanspec, 4), CalibrationError);
}
