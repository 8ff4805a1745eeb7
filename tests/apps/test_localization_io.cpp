/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPosePDFGaussian.h>
#include <mrpt/poses/CPosePDFParticles.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/obs/CommandLine.h>

#include <fstream>

#include "SyntheticWorld.h"
#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

namespace
{
std::string writeTemp(const std::string& text)
{
    const std::string path = mrpt_wifi::test::tempPath();
    std::ofstream(path) << text;
    return path;
}
}  // namespace

TEST(LocalizationCsv, ReadsColumnsInAnyOrderWithEmptyCells)
{
    TransmitterMap names = loctest::makeAps({{1, 1, 0}});
    const auto path = writeTemp(
        "# comment\n"
        "transmitter,aod_deg,timestamp,aoa_deg,aoa_std_deg,aoa_mirror_deg\n"
        "ap1,,1700000000.5,30,2,150\n"
        "02:00:00:00:0A:01,-10,1700000001.0,,,\n"
        "ap1,,1700000002.0,,,\n");
    BearingCsvOptions o;
    o.names = &names;
    o.defaultStd_rad = 0.1;
    InputWarnings w;
    const auto r = readBearingCsv(path, o, &w);
    ASSERT_EQ(r.size(), 2u);
    EXPECT_EQ(w.noAngle, 1u);
    EXPECT_TRUE(r[0].hasAoa && !r[0].hasAod && r[0].aoaAmbiguous);
    EXPECT_NEAR(r[0].aoa, mrpt::DEG2RAD(30.0), 1e-12);
    EXPECT_NEAR(r[0].aoaStd, mrpt::DEG2RAD(2.0), 1e-12);
    EXPECT_NEAR(r[0].aoaMirror, mrpt::DEG2RAD(150.0), 1e-12);
    EXPECT_TRUE(!r[1].hasAoa && r[1].hasAod);
    EXPECT_DOUBLE_EQ(r[1].aodStd, 0.1);
    EXPECT_EQ(r[1].transmitter, names.at(0).mac);
}

TEST(LocalizationCsv, ReadsCsiBearingsCsvWithFlagColumns)
{
    // The layout `csi-bearings --csv` writes: empty cells for what wasn't measured (row 3);
    // older versions wrote zeros there (row 1): the 0 flag wins, and the reader counts the
    // disowned cells so the apps can warn about them.
    const auto path = writeTemp(
        "timestamp,transmitter,channel,rssi_dbm,algorithm,aoa_deg,aoa_std_deg,aoa_ambiguous,"
        "aoa_mirror_deg,has_aod,aod_deg,aod_std_deg,aod_mirror_deg,delay_ns,quality,frames\n"
        "1700000000.06,02:00:00:00:03:02,6/20,-37,aoa_only,28.2,7.4,1,151.8,0,0.000,0.000,0.000,"
        "0,0.88,1\n"
        "1700000000.07,02:00:00:00:03:02,6/20,-37,aoa_only,28.2,7.4,0,151.8,1,10,3,170,0,0.88,1\n"
        "1700000000.08,02:00:00:00:03:02,6/20,-37,aoa_only,28.2,7.4,0,,0,,,,0,0.88,1\n");
    InputWarnings w;
    const auto r = readBearingCsv(path, {}, &w);
    ASSERT_EQ(r.size(), 3u);
    EXPECT_TRUE(r[0].hasAoa && r[0].aoaAmbiguous && !r[0].hasAod);
    EXPECT_TRUE(!r[1].aoaAmbiguous && r[1].hasAod && r[1].aodAmbiguous);
    EXPECT_TRUE(r[2].hasAoa && !r[2].aoaAmbiguous && !r[2].hasAod);
    EXPECT_EQ(w.flaggedOffAngles, 1u);
    EXPECT_NE(w.csvWarning("b.csv").find("b.csv: 1 rows"), std::string::npos);
    EXPECT_NE(w.summary().find("1 angle cells flagged"), std::string::npos);
    InputWarnings clean;
    readBearingCsv(
        writeTemp("timestamp,transmitter,has_aod,aoa_deg,aod_deg\n"
                  "1700000000.0,02:00:00:00:03:02,0,10,\n"),
        {}, &clean);
    EXPECT_TRUE(clean.csvWarning("b.csv").empty());
}

TEST(LocalizationCsv, ReadsTheAoaAlternative)
{
    // csi-bearings --csv: a window near endfire has aoa_alt_deg, its weight and the σ of each
    // direction; the others leave the three cells empty.
    const std::string header =
        "timestamp,transmitter,aoa_deg,aoa_std_deg,aoa_ambiguous,aoa_mirror_deg,aoa_alt_deg,"
        "aoa_alt_weight,aoa_direction_std_deg\n";
    const auto r = readBearingCsv(
        writeTemp(
            header + "1700000000.1,02:00:00:00:03:02,80,75,1,100,-88,0.9,4.5\n"
                     "1700000000.2,02:00:00:00:03:02,20,3,1,160,,,\n"),
        {});
    ASSERT_EQ(r.size(), 2u);
    EXPECT_TRUE(r[0].hasAoaAlternative);
    EXPECT_NEAR(r[0].aoaAlternative, mrpt::DEG2RAD(-88.0), 1e-12);
    EXPECT_DOUBLE_EQ(r[0].aoaAlternativeWeight, 0.9);
    EXPECT_NEAR(r[0].aoaDirectionStd, mrpt::DEG2RAD(4.5), 1e-12);
    EXPECT_NEAR(r[0].aoaStd, mrpt::DEG2RAD(75.0), 1e-12) << "the σ that reaches both stays";
    EXPECT_FALSE(r[1].hasAoaAlternative);
    try
    {
        readBearingCsv(
            writeTemp(header + "1700000000.1,02:00:00:00:03:02,80,75,1,100,-88,1.5,4\n"), {});
        FAIL() << "accepted a weight of 1.5";
    }
    catch (const std::runtime_error& e)
    {
        EXPECT_NE(std::string(e.what()).find(":2: aoa_alt_weight"), std::string::npos) << e.what();
    }
    // Written back (writeBearingCsv) and read again.
    const auto path = mrpt_wifi::test::tempPath();
    writeBearingCsv(path, r);
    const auto back = readBearingCsv(path, {});
    ASSERT_EQ(back.size(), 2u);
    EXPECT_TRUE(back[0].hasAoaAlternative);
    EXPECT_NEAR(back[0].aoaAlternative, r[0].aoaAlternative, 1e-4);
    EXPECT_NEAR(back[0].aoaAlternativeWeight, 0.9, 1e-4);
    EXPECT_NEAR(back[0].aoaDirectionStd, r[0].aoaDirectionStd, 1e-4);
    EXPECT_FALSE(back[1].hasAoaAlternative);
}

TEST(LocalizationCsv, ReadsSeveralAoaAlternatives)
{
    // aoa_more_alts: the second and later alternatives, "deg:weight;deg:weight".
    const std::string header =
        "timestamp,transmitter,aoa_deg,aoa_std_deg,aoa_alt_deg,aoa_alt_weight,"
        "aoa_direction_std_deg,aoa_more_alts\n";
    const auto r = readBearingCsv(
        writeTemp(header + "1700000000.1,02:00:00:00:03:02,20,3,-35,0.3,3,60:0.05;-70:0.02\n"), {});
    ASSERT_EQ(r.size(), 1u);
    const auto all = r[0].aoaAlternatives();
    ASSERT_EQ(all.size(), 3u);
    EXPECT_NEAR(all[1].aoa, mrpt::DEG2RAD(60.0), 1e-12);
    EXPECT_DOUBLE_EQ(all[2].weight, 0.02);
    const auto path = mrpt_wifi::test::tempPath();
    writeBearingCsv(path, r);
    const auto back = readBearingCsv(path, {});
    ASSERT_EQ(back.size(), 1u);
    ASSERT_EQ(back[0].aoaAlternatives().size(), 3u);
    EXPECT_NEAR(back[0].aoaAlternatives()[2].aoa, mrpt::DEG2RAD(-70.0), 1e-4);
    for (const std::string bad : {"60:0.05;-70", "60:2", "x:0.1"}) try
        {
            readBearingCsv(
                writeTemp(header + "1700000000.1,02:00:00:00:03:02,20,3,-35,0.3,3," + bad + "\n"),
                {});
            ADD_FAILURE() << "accepted '" << bad << "'";
        }
        catch (const std::runtime_error& e)
        {
            EXPECT_NE(std::string(e.what()).find(":2: aoa_more_alts"), std::string::npos)
                << e.what();
        }
}

TEST(LocalizationCsv, ErrorsNameTheLine)
{
    BearingCsvOptions o;
    auto expectError = [&](const std::string& text, const std::string& needle)
    {
        try
        {
            readBearingCsv(writeTemp(text), o);
            FAIL() << "accepted: " << text;
        }
        catch (const std::runtime_error& e)
        {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
    };
    expectError("timestamp,transmitter,aoa_deg\n1,02:00:00:00:00:01,abc\n", ":2: column 'aoa_deg'");
    expectError("timestamp,transmitter,aoa_deg\n1,kitchen-plug,3\n", "kitchen-plug");
    expectError("timestamp,aoa_deg\n", "'transmitter'");
    expectError("timestamp,transmitter\n", "'aoa_deg' or 'aod_deg'");
    expectError("", "empty");
}

TEST(LocalizationCsv, WriteReadRoundTrip)
{
    const auto w = loctest::makeWorld(loctest::makeAps({{1, 1, 0}, {5, 1, 1}}), {});
    const auto path = mrpt_wifi::test::tempPath();
    writeBearingCsv(path, w.bearings);
    const auto back = readBearingCsv(path, {});
    ASSERT_EQ(back.size(), w.bearings.size());
    for (size_t i = 0; i < back.size(); i += 37)
    {
        EXPECT_NEAR(back[i].t, w.bearings[i].t, 1e-6);
        EXPECT_NEAR(std::abs(wrapToPi(back[i].aoa - w.bearings[i].aoa)), 0, 1e-4);
        EXPECT_NEAR(std::abs(wrapToPi(back[i].aodMirror - w.bearings[i].aodMirror)), 0, 1e-4);
        EXPECT_EQ(back[i].aoaAmbiguous, w.bearings[i].aoaAmbiguous);
    }
}

TEST(LocalizationTrajectory, TumRoundTripAndInterpolation)
{
    Trajectory2D t;
    t.push_back(10.0, {0, 0, 3.0});
    t.push_back(11.0, {1, 2, -3.0});  // yaw crosses ±π
    const auto path = mrpt_wifi::test::tempPath();
    t.saveTum(path);
    const auto b = Trajectory2D::fromTumFile(path);
    ASSERT_EQ(b.size(), 2u);
    EXPECT_NEAR(b.poses[1].phi, -3.0, 1e-8);
    mrpt::math::TPose2D p;
    ASSERT_TRUE(b.interpolate(10.5, p));
    EXPECT_NEAR(p.x, 0.5, 1e-9);
    EXPECT_NEAR(std::abs(p.phi), M_PI, 1e-6);  // the short way round
    EXPECT_FALSE(b.interpolate(9.0, p));
    EXPECT_FALSE(b.interpolate(10.5, p, 0.5));  // gap too long
    EXPECT_THROW(Trajectory2D::fromTumFile(writeTemp("1 2 3\n")), std::runtime_error);
}

TEST(LocalizationTrajectory, AteAlignsRigidlyAsEvo)
{
    const auto w = loctest::makeWorld(loctest::makeAps({{1, 1, 0}}), {});
    // The truth seen from another frame: the ATE after alignment is zero, before it is not.
    const mrpt::poses::CPose2D T(3, -2, 0.7);
    Trajectory2D moved;
    for (size_t i = 0; i < w.truth.size(); i += 10)
        moved.push_back(w.truth.t[i], (T + mrpt::poses::CPose2D(w.truth.poses[i])).asTPose());
    const auto a = absoluteTrajectoryError(moved, w.truth, true);
    EXPECT_LT(a.stats.max, 1e-6);
    EXPECT_GT(absoluteTrajectoryError(moved, w.truth, false).stats.median, 1.0);
    // Drifting odometry has a real error even after alignment.
    EXPECT_GT(absoluteTrajectoryError(w.odometry, w.truth, true).stats.median, 0.1);
    // No overlap in time: an error, not a number.
    Trajectory2D late;
    late.push_back(2e9, {0, 0, 0});
    late.push_back(2e9 + 1, {0, 0, 0});
    EXPECT_THROW(absoluteTrajectoryError(late, w.truth), std::runtime_error);
}

TEST(LocalizationTrajectory, AteWithCorrectScaleRemovesOnlyTheScale)
{
    const auto w = loctest::makeWorld(loctest::makeAps({{1, 1, 0}}), {});
    // The truth 3 % too small, seen from another frame (odometry with a scale error): rigid
    // alignment leaves an error, a similarity none, and says by how much it scaled.
    const mrpt::poses::CPose2D T(3, -2, 0.7);
    Trajectory2D shrunk, bent;
    for (size_t i = 0; i < w.truth.size(); i += 10)
    {
        auto p = w.truth.poses[i];
        p.x *= 0.97, p.y *= 0.97;
        shrunk.push_back(w.truth.t[i], (T + mrpt::poses::CPose2D(p)).asTPose());
        p.y += 0.3 * std::sin(p.x);  // and a shape error no scale can remove
        bent.push_back(w.truth.t[i], (T + mrpt::poses::CPose2D(p)).asTPose());
    }
    EXPECT_GT(absoluteTrajectoryError(shrunk, w.truth).stats.max, 0.01);
    const auto sim = absoluteTrajectoryError(shrunk, w.truth, true, true);
    EXPECT_LT(sim.stats.max, 1e-6);
    EXPECT_NEAR(sim.scale, 1 / 0.97, 1e-6);
    EXPECT_NEAR(absoluteTrajectoryError(shrunk, w.truth).scale, 1.0, 0);
    EXPECT_GT(absoluteTrajectoryError(bent, w.truth, true, true).stats.median, 0.05);
    // The alignment of the same points with the similarity: the frame and the scale back.
    std::vector<mrpt::math::TPoint2D> a, b;
    for (size_t i = 0; i < shrunk.size(); ++i)
        a.emplace_back(shrunk.poses[i].x, shrunk.poses[i].y),
            b.emplace_back(w.truth.poses[i * 10].x, w.truth.poses[i * 10].y);
    const auto s = alignSimilarity2D(a, b);
    EXPECT_NEAR(s.scale, 1 / 0.97, 1e-6);
    EXPECT_NEAR(mrpt::math::wrapToPi(s.pose.phi), -0.7, 1e-6);
    EXPECT_THROW(alignSimilarity2D({{0, 0}}, {{1, 1}}), std::invalid_argument);
}

TEST(LocalizationRawlog, PfRawlogRoundTrip)
{
    const auto w = loctest::makeWorld(loctest::makeAps({{1, 1, 0}}), {});
    const auto path = mrpt_wifi::test::tempPath() + ".rawlog";
    const size_t n = writePfRawlog(path, w.bearings, w.odometry);
    EXPECT_EQ(n, w.bearings.size() + w.odometry.size());
    const auto c = readRawlog(path);
    ASSERT_EQ(c.bearings.size(), w.bearings.size());
    EXPECT_EQ(c.odometry.size(), w.odometry.size());
    EXPECT_NEAR(c.bearings[5].aoa, w.bearings[5].aoa, 1e-12);
    EXPECT_NEAR(c.bearings[5].sensorPose.x, 0.1, 1e-12);
    EXPECT_EQ(c.otherObservations, 0u);
}

TEST(LocalizationUnknownMotion, ConstantVelocityPredictsFromRecentEstimates)
{
    // Issue 12.3: without odometry each filter step is predicted from the filter's own estimates
    // (constant velocity, robot frame), bounded by the top speed; no history, no prediction.
    UnknownMotion m;
    m.maxSpeed_mps = 0.6, m.velocityWindow_s = 1.0;
    ConstantVelocityPrediction cv(m);
    EXPECT_EQ(cv.predictIncrement(0.1), mrpt::poses::CPose2D());
    // Moving north at 0.4 m/s while the heading turns 10 deg/s, from 90 to 110 deg: the world
    // velocity in the newest estimate's frame (20 deg to its right).
    for (int i = 0; i <= 40; ++i)
    {
        const double t = 0.05 * i;
        cv.addEstimate(t, {3.0, 1.0 + 0.4 * t, M_PI / 2 + mrpt::DEG2RAD(10.0) * t});
    }
    const auto inc = cv.predictIncrement(2.0 + 0.1);
    EXPECT_NEAR(inc.x(), 0.04 * std::cos(mrpt::DEG2RAD(20.0)), 1e-6);
    EXPECT_NEAR(inc.y(), -0.04 * std::sin(mrpt::DEG2RAD(20.0)), 1e-6);
    EXPECT_NEAR(mrpt::RAD2DEG(inc.phi()), 1.0, 1e-6);
    // The action is that increment with the random walk's sigma around it.
    const auto a = m.makeAction(0.1, inc);
    const auto mean = a->poseChange->getMeanVal();
    EXPECT_NEAR(mean.x(), inc.x(), 1e-9);
    EXPECT_NEAR(mean.phi(), inc.phi(), 1e-9);
    // A jumping estimate (not converged yet) never predicts more than the top speed.
    cv.addEstimate(2.1, {8.0, 1.0, M_PI / 2});
    EXPECT_LE(cv.predictIncrement(2.2).norm(), 0.6 * 0.1 + 1e-9);
    // Time going backwards (a new run of the filter) forgets the history.
    cv.addEstimate(0.0, {3.0, 1.0, 0.0});
    EXPECT_EQ(cv.predictIncrement(0.1), mrpt::poses::CPose2D());
    // Switched off: the zero-mean walk.
    m.constantVelocity = false;
    ConstantVelocityPrediction off(m);
    for (int i = 0; i <= 40; ++i) off.addEstimate(0.05 * i, {0.4 * 0.05 * i, 0, 0});
    EXPECT_EQ(off.predictIncrement(2.1), mrpt::poses::CPose2D());
}

TEST(CommandLineJoinedArgv, SeparateOrQuotedNumbersAndNothingMore)
{
    // `--initial-pose 2 1.5 0` and `--initial-pose "2 1.5 0"` are the same, and the quoted form
    // must not swallow the options after it (it once ate `--odometry-drift 0 0`).
    const auto joined = [](std::vector<std::string> a)
    {
        std::vector<char*> argv;
        for (auto& s : a) argv.push_back(s.data());
        mrpt_wifi::cli::JoinedArgv j(int(argv.size()), argv.data(), "--initial-pose", 3);
        return std::vector<std::string>(j.argv(), j.argv() + j.argc());
    };
    using V = std::vector<std::string>;
    EXPECT_EQ(
        joined({"app", "--initial-pose", "2", "1.5", "0", "-q"}),
        V({"app", "--initial-pose", "2 1.5 0", "-q"}));
    EXPECT_EQ(
        joined({"app", "--initial-pose", "2 1.5 0", "--odometry-drift", "0 0"}),
        V({"app", "--initial-pose", "2 1.5 0", "--odometry-drift", "0 0"}));
    EXPECT_EQ(
        joined({"app", "--initial-pose", "2 1.5", "0", "-q"}),
        V({"app", "--initial-pose", "2 1.5 0", "-q"}));
    // Too few: what there is, for the pose parser to reject with its message.
    EXPECT_EQ(joined({"app", "--initial-pose", "2"}), V({"app", "--initial-pose", "2"}));
}

TEST(ConstantVelocityPrediction, ForwardOnlyMovesAlongTheHeading)
{
    // Estimates drifting sideways (noise of the PF mean) while the robot faces +x at 0.5 m/s:
    // the plain prediction carries the sideways motion on; forward_only keeps the speed along
    // the heading only.
    mrpt_wifi::localization::UnknownMotion m;
    m.maxSpeed_mps = 1.0, m.velocityWindow_s = 1.0;
    mrpt_wifi::localization::ConstantVelocityPrediction plain(m);
    m.forwardOnly = true;
    mrpt_wifi::localization::ConstantVelocityPrediction forward(m);
    for (int k = 0; k <= 10; ++k)
    {
        const mrpt::math::TPose2D p(0.05 * k, 0.02 * k, 0);
        plain.addEstimate(0.1 * k, p);
        forward.addEstimate(0.1 * k, p);
    }
    const auto a = plain.predictIncrement(1.1), b = forward.predictIncrement(1.1);
    EXPECT_NEAR(a.x(), 0.05, 1e-9);
    EXPECT_NEAR(a.y(), 0.02, 1e-9);
    EXPECT_NEAR(b.x(), 0.05, 1e-9);
    EXPECT_NEAR(b.y(), 0.0, 1e-12);
    // Read from the .ini like the other keys.
    mrpt::config::CConfigFileMemory ini("[UnknownMotion]\nforward_only = true\n");
    mrpt_wifi::localization::UnknownMotion r;
    r.loadFromConfigFile(ini, "UnknownMotion");
    EXPECT_TRUE(r.forwardOnly);
}

TEST(UnknownMotion, BearingWeightIsReadAndOutsideZeroOneNamesTheKey)
{
    mrpt::config::CConfigFileMemory ini("[UnknownMotion]\nbearing_weight = 0.5\n");
    mrpt_wifi::localization::UnknownMotion r;
    EXPECT_EQ(r.bearingWeight, 1.0);  // untempered unless the .ini says so
    r.loadFromConfigFile(ini, "UnknownMotion");
    EXPECT_EQ(r.bearingWeight, 0.5);
    EXPECT_NE(r.asString().find("bearings weighted 0.5"), std::string::npos) << r.asString();
    for (const std::string value : {"0", "1.5", "-0.2"})
    {
        mrpt::config::CConfigFileMemory bad("[UnknownMotion]\nbearing_weight = " + value + "\n");
        try
        {
            mrpt_wifi::localization::UnknownMotion().loadFromConfigFile(bad, "UnknownMotion");
            ADD_FAILURE() << "accepted bearing_weight = " << value;
        }
        catch (const std::invalid_argument& e)
        {
            EXPECT_NE(std::string(e.what()).find("bearing_weight"), std::string::npos) << e.what();
        }
    }
}

TEST(UnknownMotion, WideFractionMakesTheWalkHeavyTailed)
{
    // Issue 12.3: a tight walk for straight drives, with a few wide steps for the turns the
    // constant-velocity prediction misses: the step is drawn from a mixture.
    mrpt_wifi::localization::UnknownMotion m;
    m.maxSpeed_mps = 0.6, m.correlationTime_s = 0.05;
    m.wideFraction = 0.1, m.wideCorrelationTime_s = 1.0;
    const double dt = 0.1, narrow = m.stdXY(dt);
    mrpt::random::getRandomGenerator().randomize(7);
    const auto a = m.makeAction(dt, mrpt::poses::CPose2D(0.06, 0, 0));
    const auto* pdf = dynamic_cast<const mrpt::poses::CPosePDFParticles*>(a->poseChange.get());
    ASSERT_NE(pdf, nullptr);
    // Drawn the way MRPT's filter draws a particle's step.
    size_t far = 0;
    const size_t n = 20000;
    double sum = 0;
    for (size_t i = 0; i < n; ++i)
    {
        mrpt::poses::CPose2D d;
        pdf->drawSingleSample(d);
        sum += d.x();
        if (std::abs(d.x() - 0.06) > 4 * narrow) ++far;
    }
    EXPECT_NEAR(sum / n, 0.06, 3 * m.stdXY(dt) / std::sqrt(double(n)) + 0.01);
    // |x| > 4 sigma of the narrow part: ~never from it, ~37 % of the wide steps (sigma 4.5x),
    // so ~3.7 % of all (50 wide samples: +-0.7 % at 1 sigma; seeded).
    EXPECT_GT(double(far) / n, 0.015);
    EXPECT_LT(double(far) / n, 0.07);
    // Without the wide part the action stays MRPT's Gaussian.
    m.wideFraction = 0;
    EXPECT_NE(
        dynamic_cast<const mrpt::poses::CPosePDFGaussian*>(m.makeAction(dt)->poseChange.get()),
        nullptr);
    m.wideFraction = 1.5;
    EXPECT_THROW(m.validate(), std::invalid_argument);
}

TEST(OdometryMotion, SpreadGrowsWithTimeAndDistanceNotWithTheStepCount)
{
    // MRPT's Gaussian model adds its floors once per filter step: at 150 bearings/s a walk of
    // 6 deg/sqrt(s) that drowns the odometry. This model's variance is linear in the time and
    // in the distance of a step, so a drive cut into ten steps spreads as much as in one.
    OdometryMotion m;
    m.jumpRate_hz = 0;
    m.stdXY_per_sqrt_m = 0.03, m.stdPhi_deg_per_sqrt_m = 1.0;
    m.stdXY_per_sqrt_s = 0.02, m.stdPhi_deg_per_sqrt_s = 0.5;
    const mrpt::poses::CPose2D oneStep(0.3, 0, 0), tenthStep(0.03, 0, 0);
    const auto a = m.makeAction(0.5, oneStep), b = m.makeAction(0.05, tenthStep);
    const auto* g = dynamic_cast<const mrpt::poses::CPosePDFGaussian*>(a->poseChange.get());
    ASSERT_NE(g, nullptr);
    EXPECT_NEAR(g->mean.x(), 0.3, 1e-12);
    EXPECT_NEAR(g->mean.y(), 0.0, 1e-12);
    const double varXY = 0.03 * 0.03 * 0.3 + 0.02 * 0.02 * 0.5;
    // (MRPT's model keeps its σ as float; sideways it adds the heading noise times the step.)
    EXPECT_NEAR(g->cov(0, 0), varXY, 1e-3 * varXY);
    EXPECT_NEAR(g->cov(1, 1), varXY, 0.05 * varXY);
    const double varPhi =
        std::pow(mrpt::DEG2RAD(1.0), 2) * 0.3 + std::pow(mrpt::DEG2RAD(0.5), 2) * 0.5;
    EXPECT_NEAR(g->cov(2, 2), varPhi, 1e-3 * varPhi);
    const auto cb = b->poseChange->getCovariance();
    EXPECT_NEAR(10 * cb(0, 0), g->cov(0, 0), 1e-3 * varXY);
    EXPECT_NEAR(10 * cb(2, 2), g->cov(2, 2), 1e-3 * varPhi);
    // Standing still, only time spreads it; a zero step is not singular.
    EXPECT_NEAR(m.stdXY(1.0, 0), 0.02, 1e-12);
    EXPECT_NO_THROW(m.makeAction(0, {}));

    // Heavy-tailed: jumps at a rate per second, so in a step of 0.5 s a tenth of the particles
    // jump (1 - exp(-rate * dt)), here by ten times the step's own sigma.
    const double sigma = std::sqrt(varXY);
    m.jumpRate_hz = -std::log(0.9) / 0.5, m.jumpStdXY_m = std::sqrt(99.0) * sigma;
    m.jumpStdPhi_deg = 0;
    mrpt::random::getRandomGenerator().randomize(3);
    const auto w = m.makeAction(0.5, oneStep);
    const auto* pdf = dynamic_cast<const mrpt::poses::CPosePDFParticles*>(w->poseChange.get());
    ASSERT_NE(pdf, nullptr);
    const auto farShare = [&](const mrpt::poses::CPosePDFParticles& p, double mean, double bound)
    {
        size_t far = 0;
        const size_t n = 20000;
        for (size_t i = 0; i < n; ++i)
        {
            mrpt::poses::CPose2D d;
            p.drawSingleSample(d);
            if (std::abs(d.x() - mean) > bound) ++far;
        }
        return double(far) / n;
    };
    // Beyond 4 sigma: ~0 of the tight part, 69 % of the jumps (beyond 0.4 of their sigma), so
    // ~6.9 % of all (50 jump samples: +-0.6 % at 1 sigma).
    EXPECT_GT(farShare(*pdf, 0.3, 4 * sigma), 0.035);
    EXPECT_LT(farShare(*pdf, 0.3, 4 * sigma), 0.10);
    // Per time, not per step: a tenth of the time keeps a particle jump-free with probability
    // 0.9^(1/10), so ten such steps jump as often in all as the one of 0.5 s. Beyond 6 sigma of
    // this small step's tight part lie ~0 of it and the jumps' Gaussian tail beyond that bound.
    const auto w10 = m.makeAction(0.05, tenthStep);
    const auto* pdf10 = dynamic_cast<const mrpt::poses::CPosePDFParticles*>(w10->poseChange.get());
    ASSERT_NE(pdf10, nullptr);
    const double sigma10 = m.stdXY(0.05, 0.03), bound10 = 6 * sigma10;
    const double jumpShare10 = 1 - std::pow(0.9, 0.1);
    const double jumpSigma10 = std::hypot(sigma10, m.jumpStdXY_m);
    const double expected10 = jumpShare10 * std::erfc(bound10 / (std::sqrt(2.0) * jumpSigma10));
    // 50 jump samples: ~+-5 % of the share; 20000 draws: +-0.0007 at 1 sigma.
    EXPECT_NEAR(farShare(*pdf10, 0.03, bound10), expected10, 0.004);

    // Read from the .ini; bad values name the key.
    mrpt::config::CConfigFileMemory ini(
        "[OdometryMotion]\nstd_xy_per_sqrt_m = 0.05\njump_rate_hz = 0.25\njump_std_xy_m = 0.2\n"
        "jump_std_phi_deg = 4\nbearing_weight = 0.3\n");
    OdometryMotion r;
    r.loadFromConfigFile(ini, "OdometryMotion");
    EXPECT_EQ(r.stdXY_per_sqrt_m, 0.05);
    EXPECT_EQ(r.jumpRate_hz, 0.25);
    EXPECT_EQ(r.jumpStdXY_m, 0.2);
    EXPECT_EQ(r.jumpStdPhi_deg, 4);
    EXPECT_EQ(r.bearingWeight, 0.3);
    for (const std::string key :
         {"std_phi_deg_per_sqrt_s = -1", "bearing_weight = 1.5", "jump_rate_hz = -0.1"})
    {
        mrpt::config::CConfigFileMemory bad("[OdometryMotion]\n" + key + "\n");
        try
        {
            OdometryMotion(r).loadFromConfigFile(bad, "OdometryMotion");
            ADD_FAILURE() << "accepted " << key;
        }
        catch (const std::invalid_argument& e)
        {
            EXPECT_NE(std::string(e.what()).find(key.substr(0, key.find(' '))), std::string::npos)
                << e.what();
        }
    }
}
