/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <gtest/gtest.h>
#include <mrpt/poses/CPosePDFGaussianInf.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/BearingGraphSlam.h>
#include <mrpt_wifi/localization/DeviceMapper.h>

#include "SyntheticWorld.h"
#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;
using namespace mrpt_wifi::loctest;

namespace
{
TransmitterMap hallAps()
{
    return makeAps(
        {{0.5, 6.5, -0.785}, {10.5, 6.5, -2.36}, {10.5, -0.5, 2.36}, {0.5, -0.5, 0.785}});
}
WorldOptions hallLoop()
{
    WorldOptions o;
    o.duration_s = 240;
    o.loop = {{2, 1}, {9, 1}, {9, 5}, {2, 5}};
    return o;
}
}  // namespace

TEST(GraphSlamKnownAps, HalvesTheMedianAteOfOdometry)
{
    const auto w = makeWorld(hallAps(), hallLoop());
    GraphSlamInput in;
    in.odometry = w.odometry;
    in.bearings = w.bearings;
    in.aps = w.aps;
    GraphSlamOptions o;
    o.apsKnown = true;
    const auto r = solveBearingGraph(in, o);
    const auto ate = absoluteTrajectoryError(r.poses, w.truth);
    const auto odo = absoluteTrajectoryError(r.initialPoses, w.truth);
    EXPECT_LT(ate.stats.median, 0.5 * odo.stats.median)
        << "slam " << ate.stats.asString() << " odometry " << odo.stats.asString();
    EXPECT_LT(ate.stats.median, 0.15) << ate.stats.asString();
    EXPECT_EQ(r.aoaEdges, w.bearings.size());
    EXPECT_EQ(r.aodEdges, w.bearings.size());
    // Known APs fix the frame: the solution is in the world frame without alignment.
    EXPECT_LT(absoluteTrajectoryError(r.poses, w.truth, false).stats.median, 0.2);
    EXPECT_EQ(r.graph.nodes.size(), r.poses.size() + 4);
    EXPECT_EQ(r.graph.edges.size(), r.poses.size() - 1);
}

TEST(GraphSlamKnownAps, ClearPlacementNeverInitialisesUnknownAps)
{
    // Issue 56: with known APs the unknown-AP machinery (triangulating every AP from rays on
    // the drifting odometry, the estimated-AP solution) ran on every call and took nearly all
    // of the 13 minutes of a 30-minute building drive. When every AP is heard from the start it
    // must not run at all; when the start can't place the trajectory it still does.
    WorldOptions wo = hallLoop();
    wo.duration_s = 120;
    const auto w = makeWorld(hallAps(), wo);
    GraphSlamInput in;
    in.odometry = w.odometry;
    in.bearings = w.bearings;
    in.aps = w.aps;
    GraphSlamOptions o;
    o.apsKnown = true;
    std::vector<std::string> lines;
    o.progress = [&](const std::string& line) { lines.push_back(line); };
    const auto r = solveBearingGraph(in, o);
    EXPECT_EQ(r.apTriangulations, 0u) << r.placement;
    for (const auto& p : r.phases) EXPECT_NE(p.name, "unknown-AP initialisation");
    EXPECT_LT(absoluteTrajectoryError(r.poses, w.truth).stats.median, 0.15);
    // Progress: the placement search and each solve, one line each.
    ASSERT_FALSE(lines.empty());
    EXPECT_NE(lines.front().find("placement search"), std::string::npos) << lines.front();
    EXPECT_LT(lines.size(), 10u);

    // Only one AP heard in the first 40 s: the placement is ambiguous, the estimated-AP start
    // runs (and triangulates).
    std::vector<BearingRecord> late;
    for (const auto& b : w.bearings)
        if (b.t >= w.truth.t.front() + 40 || b.transmitter == w.aps.at(0).mac) late.push_back(b);
    in.bearings = late;
    o.progress = nullptr;
    const auto doubtful = solveBearingGraph(in, o);
    EXPECT_GT(doubtful.apTriangulations, 0u);
}

TEST(GraphSlamUnknownAps, EstimatesApsAndTrajectory)
{
    const auto w = makeWorld(hallAps(), hallLoop());
    GraphSlamInput in;
    in.odometry = w.odometry;
    in.bearings = w.bearings;
    const auto r = solveBearingGraph(in, GraphSlamOptions());
    const auto ate = absoluteTrajectoryError(r.poses, w.truth);
    const auto odo = absoluteTrajectoryError(r.initialPoses, w.truth);
    EXPECT_LT(ate.stats.median, 0.5 * odo.stats.median)
        << "slam " << ate.stats.asString() << " odometry " << odo.stats.asString();
    ASSERT_EQ(r.aps.size(), 4u);
    // APs in the odometry frame: map them with the trajectory's alignment to compare.
    const mrpt::poses::CPose2D T(ate.alignment);
    for (const auto& ap : r.aps.transmitters())
    {
        const auto* truth = w.aps.find(ap.mac);
        ASSERT_TRUE(truth);
        const auto p = T.composePoint(mrpt::math::TPoint2D(ap.pose.x, ap.pose.y));
        EXPECT_LT(std::hypot(p.x - truth->pose.x, p.y - truth->pose.y), 0.5) << ap.name;
    }
}

TEST(GraphSlamBadInput, EmptyUnconnectedAndNonOverlapping)
{
    const auto w = makeWorld(hallAps(), hallLoop());
    GraphSlamInput in;
    in.bearings = w.bearings;
    EXPECT_THROW(solveBearingGraph(in, {}), std::runtime_error);  // no odometry

    // Bearings that never overlap the odometry's time span.
    in.odometry = w.odometry;
    auto shifted = w.bearings;
    for (auto& b : shifted) b.t += 1e6;
    in.bearings = shifted;
    try
    {
        solveBearingGraph(in, {});
        FAIL() << "non-overlapping bearings accepted";
    }
    catch (const std::runtime_error& e)
    {
        EXPECT_NE(std::string(e.what()).find("overlap"), std::string::npos) << e.what();
    }

    // An MRPT graph with a missing edge: two pieces.
    mrpt::graphs::CNetworkOfPoses2DInf g;
    Trajectory2D times;
    for (size_t k = 0; k < 4; ++k)
    {
        g.nodes[k] = mrpt::poses::CPose2D(k, 0, 0);
        times.push_back(w.odometry.t[k * 20], {double(k), 0, 0});
    }
    mrpt::poses::CPosePDFGaussianInf e;
    e.mean = mrpt::poses::CPose2D(1, 0, 0);
    e.cov_inv.setIdentity();
    g.insertEdge(0, 1, e);
    g.insertEdge(2, 3, e);
    in.odometry = times;
    in.graph = &g;
    in.bearings = w.bearings;
    try
    {
        solveBearingGraph(in, {});
        FAIL() << "unconnected graph accepted";
    }
    catch (const std::runtime_error& ex)
    {
        EXPECT_NE(std::string(ex.what()).find("not connected"), std::string::npos) << ex.what();
    }
}

TEST(GraphSlamBadInput, UnknownTransmittersAreCounted)
{
    auto w = makeWorld(hallAps(), hallLoop());
    GraphSlamInput in;
    in.odometry = w.odometry;
    in.bearings = w.bearings;
    BearingRecord stray = w.bearings.front();
    stray.transmitter = MacAddress::fromString("02:00:00:00:ee:ee");
    in.bearings.push_back(stray);
    in.bearings.push_back(stray);
    in.aps = w.aps;
    GraphSlamOptions o;
    o.apsKnown = true;
    const auto r = solveBearingGraph(in, o);
    EXPECT_EQ(r.warnings.unknownTransmitter, 2u);
}

TEST(GraphSlamMrptGraph, OdometryFromAnMrptGraphFile)
{
    // The odometry as an MRPT pose graph on disk (VERTEX_SE2 / EDGE_SE2) + a TUM file of its
    // node times: the same correction as from raw odometry.
    const auto w = makeWorld(hallAps(), hallLoop());
    mrpt::graphs::CNetworkOfPoses2DInf g;
    Trajectory2D times;
    for (size_t i = 0, k = 0; i < w.odometry.size(); i += 10, ++k)
    {
        g.nodes[k] = mrpt::poses::CPose2D(w.odometry.poses[i]);
        times.push_back(w.odometry.t[i], w.odometry.poses[i]);
        if (k == 0) continue;
        mrpt::poses::CPosePDFGaussianInf e;
        e.mean = g.nodes[k] - g.nodes[k - 1];
        e.cov_inv.setZero();
        e.cov_inv(0, 0) = e.cov_inv(1, 1) = 1 / (0.03 * 0.03);
        e.cov_inv(2, 2) = 1 / (0.02 * 0.02);
        g.insertEdge(k - 1, k, e);
    }
    const std::string path = mrpt_wifi::test::tempPath() + ".graph";
    g.saveToTextFile(path);
    mrpt::graphs::CNetworkOfPoses2DInf loaded;
    loaded.loadFromTextFile(path);
    GraphSlamInput in;
    in.graph = &loaded;
    in.odometry = times;
    in.bearings = w.bearings;
    in.aps = w.aps;
    GraphSlamOptions o;
    o.apsKnown = true;
    const auto r = solveBearingGraph(in, o);
    EXPECT_EQ(r.poses.size(), times.size());
    EXPECT_EQ(r.odometryEdges, times.size() - 1);
    const auto ate = absoluteTrajectoryError(r.poses, w.truth);
    const auto odo = absoluteTrajectoryError(r.initialPoses, w.truth);
    EXPECT_LT(ate.stats.median, 0.5 * odo.stats.median)
        << "slam " << ate.stats.asString() << " odometry " << odo.stats.asString();
}

namespace
{
/** Median ATE reduction vs odometry [%] of graph SLAM with known or estimated APs. */
double ateReduction(const World& w, bool apsKnown)
{
    GraphSlamInput in;
    in.odometry = w.odometry;
    in.bearings = w.bearings;
    in.aps = w.aps;
    GraphSlamOptions o;
    o.apsKnown = apsKnown;
    o.useAod = false;
    const auto r = solveBearingGraph(in, o);
    const double odo = absoluteTrajectoryError(w.odometry, w.truth).stats.median;
    const double slam = absoluteTrajectoryError(r.poses, w.truth).stats.median;
    return 100.0 * (odo - slam) / odo;
}
}  // namespace

TEST(GraphSlamKnownAps, AoaOnlyKnownApsNeverWorseThanEstimated)
{
    // Issue 12.1: when the start of the drive can't tell where the trajectory lies among the
    // APs (here only one AP is heard in the first 40 s; with real bearings, symmetric AP layouts
    // and the mirror ambiguity of linear arrays do the same), the old single placement over the
    // first 30 s picked a wrong mode: known APs gave 30 % / 33 % median ATE reduction where
    // estimated APs gave 79 % / 52 % on these seeds. Knowing the APs must give at least what
    // estimating them gives (5 points slack).
    for (const uint64_t seed : {31u, 32u})
    {
        WorldOptions o;
        o.duration_s = 120;
        o.aod = false;
        o.aoaStd = 0.1, o.outliers = 0.08;
        o.odoScaleError = 0.04, o.odoYawDrift = 0.02;
        o.seed = seed;
        World w = makeWorld(
            makeAps({{0.3, 4.7, -0.785}, {9.7, 4.7, -2.36}, {9.7, 0.3, 2.36}, {0.3, 0.3, 0.785}}),
            o);
        const double tLate = w.truth.t.front() + 40;
        std::vector<BearingRecord> kept;
        for (const auto& b : w.bearings)
            if (b.t >= tLate || b.transmitter == w.aps.at(0).mac) kept.push_back(b);
        w.bearings = kept;
        const double known = ateReduction(w, true), est = ateReduction(w, false);
        std::cout << "seed " << seed << ": median ATE reduction known APs " << known
                  << " %, estimated " << est << " %\n";
        EXPECT_GE(known, est - 5) << "seed " << seed;
        EXPECT_GT(known, 50) << "seed " << seed;
    }
}

namespace
{
/** Issue 19.1's scene: a 12 x 8 m room, 4 APs in the corners facing the centre, 5 laps of a
 *  rectangle at 0.5 m/s, 8 AoA per AP and second (1.5 deg, 3 % outliers, no AoD), odometry 3 %
 *  long with a heading bias of 0.5 deg/s (1 deg/m): 120 deg of heading drift over the drive. */
World driftingFiveLaps(uint64_t seed)
{
    const double c = std::atan2(3.5, 5.5);  // corner -> centre
    const auto aps =
        makeAps({{0.5, 7.5, -c}, {11.5, 7.5, c - M_PI}, {11.5, 0.5, M_PI - c}, {0.5, 0.5, c}});
    WorldOptions o;
    o.loop = {{2, 2}, {10, 2}, {10, 6}, {2, 6}};
    o.duration_s = 5 * 24 / 0.5;
    o.rate_Hz = 8;
    o.aod = false;
    o.aoaStd = mrpt::DEG2RAD(1.5);
    o.odoScaleError = 0.03;
    o.odoYawDrift = mrpt::DEG2RAD(1.0);
    o.seed = seed;
    return makeWorld(aps, o);
}

/** The world's odometry and bearings, APs unknown. */
GraphSlamInput unknownApsInput(const World& w)
{
    GraphSlamInput in;
    in.odometry = w.odometry;
    in.bearings = w.bearings;
    return in;
}
}  // namespace

TEST(GraphSlamUnknownAps, SurvivesStrongHeadingDriftOverFiveLaps)
{
    // The start from APs triangulated on the whole drifting odometry ends in a local minimum
    // on this scene (Ceres: NO_CONVERGENCE at 100 iterations, trajectory worse than odometry);
    // the start grown window by window must correct the drift, and the solve must converge.
    for (const uint64_t seed : {1, 2, 3})
    {
        const World w = driftingFiveLaps(seed);
        const auto r = solveBearingGraph(unknownApsInput(w), GraphSlamOptions());
        const auto ate = absoluteTrajectoryError(r.poses, w.truth);
        const auto odo = absoluteTrajectoryError(r.initialPoses, w.truth);
        const double reduction = 1 - ate.stats.median / odo.stats.median;
        EXPECT_GE(reduction, 0.6) << "seed " << seed << ": slam " << ate.stats.asString()
                                  << " odometry " << odo.stats.asString() << " start "
                                  << r.placement;
        EXPECT_TRUE(r.converged) << "seed " << seed << ": " << r.solverReport;
        EXPECT_LT(r.medianResidual_deg, 3) << "seed " << seed;
        EXPECT_EQ(r.hypotheses, 2u);
    }
}

TEST(GraphSlamUnknownAps, ReportsWhenCeresDidNotConverge)
{
    const World w = driftingFiveLaps(1);
    GraphSlamOptions o;
    o.maxIterations = 1;
    o.growthWindow_s = 0;  // one start, one Ceres iteration: cannot converge
    const auto r = solveBearingGraph(unknownApsInput(w), o);
    EXPECT_FALSE(r.converged) << r.solverReport;
    EXPECT_EQ(r.hypotheses, 1u);
}

TEST(GraphSlamUnknownAps, ApCovarianceCoversMultipathAndOdometryBias)
{
    // Issue 19.3: the device map's 95 % ellipses held 17 % of the devices over the evaluation
    // rooms. Thousands of bearings counted as independent although multipath makes those taken
    // close together err alike, and the odometry's scale error (which bearings cannot see) was
    // no part of the model. With bearings decorrelated per 0.5 m cell and the odometry's scale
    // and heading drift estimated with their priors, the ellipses hold the APs; without, they
    // do not. AP positions are compared in the frame of the first pose (the gauge), which the
    // truth's start gives.
    size_t inside[2] = {0, 0}, aps = 0;
    for (const uint64_t seed : {11, 12, 13})
    {
        WorldOptions o = hallLoop();
        o.duration_s = 150, o.rate_Hz = 10, o.aod = false, o.seed = seed;
        o.aoaStd = mrpt::DEG2RAD(2), o.multipathAmplitude = mrpt::DEG2RAD(4);
        o.odoScaleError = seed == 12 ? -0.025 : 0.025, o.odoYawDrift = mrpt::DEG2RAD(0.4);
        const World w = makeWorld(hallAps(), o);
        const mrpt::poses::CPose2D start(w.truth.poses.front());
        for (int honest = 0; honest < 2; ++honest)
        {
            GraphSlamOptions opt;  // the defaults: decorrelated, biases estimated
            opt.apCovariance = true, opt.useAod = false;
            if (!honest)
            {
                opt.bearingDecorrelation_m = 0;
                opt.odoScaleStd = 0, opt.odoYawDriftStd_radPerM = 0;
            }
            const auto r = solveBearingGraph(unknownApsInput(w), opt);
            ASSERT_TRUE(r.apCovarianceOk) << "seed " << seed;
            ASSERT_EQ(r.aps.size(), 4u);
            for (size_t j = 0; j < r.aps.size(); ++j)
            {
                const auto& ap = r.aps.transmitters()[j];
                const auto p = start.composePoint(mrpt::math::TPoint2D(ap.pose.x, ap.pose.y));
                const auto* truth = w.aps.find(ap.mac);
                ASSERT_TRUE(truth);
                const double ex = p.x - truth->pose.x, ey = p.y - truth->pose.y;
                // The covariance is in the odometry frame: rotate the error into it.
                const double c = std::cos(start.phi()), s = std::sin(start.phi());
                const double u = c * ex + s * ey, v = -s * ex + c * ey;
                const auto& C = r.apCov[j];
                const double d2 = mahalanobis2(C[0], C[1], C[2], u, v);
                inside[honest] += d2 <= kChi2TwoDof95;
                aps += honest;
                std::cout << "seed " << seed << (honest ? " honest " : " naive  ") << ap.name
                          << ": error " << std::hypot(ex, ey) << " m, sigma "
                          << std::sqrt(0.5 * (C[0] + C[2])) << " m, d2 " << d2 << "\n";
            }
            if (honest)
            {
                EXPECT_NEAR(mrpt::RAD2DEG(r.odometryYawDrift_radPerM), -0.4, 0.2)
                    << "seed " << seed << " (the odometry turns 0.4 deg/m too far)";
            }
        }
    }
    EXPECT_GE(inside[1], aps - 1) << "decorrelated, biases estimated: " << inside[1] << " of "
                                  << aps;
    EXPECT_LE(inside[0], aps / 2) << "independent bearings: " << inside[0] << " of " << aps;
}
