/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-graphslam: odometry drift correction with WiFi bearings. A pose graph from odometry (a
 * rawlog, a TUM file or an MRPT .graph), AP nodes (known or estimated), AoA and AoD bearing edges
 * with a robust loss, solved with Ceres; writes an MRPT .graph (CNetworkOfPoses2DInf), TUM
 * trajectories, the APs, the absolute trajectory error (as evo computes it) and plots. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/BearingGraphSlam.h>
#include <mrpt_wifi/localization/Plot.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/obs/CommandLine.h>

#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "McapOutput.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

int main(int argc, char** argv)
{
    return cli::runMain(
        "wifi-graphslam",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Graph SLAM with WiFi bearing edges: odometry + AoA/AoD bearings (+ known or "
                "estimated APs) solved with Ceres. Writes an MRPT .graph, TUM trajectories and "
                "the APs; with ground truth, the absolute trajectory error vs odometry alone.",
                ' ', "0.1");
            TCLAP::ValueArg<std::string> argRawlog(
                "r", "rawlog", "Rawlog with CObservationWiFiBearing + CObservationOdometry", false,
                "", "IN.rawlog", cmd);
            TCLAP::ValueArg<std::string> argCsv(
                "b", "bearings-csv", "Bearings CSV (see share/localization/README.md)", false, "",
                "B.csv", cmd);
            TCLAP::ValueArg<std::string> argOdo(
                "", "odometry-tum", "Odometry (TUM); with --graph: the times of its nodes", false,
                "", "ODO.txt", cmd);
            TCLAP::ValueArg<std::string> argGraph(
                "", "graph",
                "Odometry pose graph (MRPT .graph, VERTEX_SE2/EDGE_SE2); node k at "
                "row k of --odometry-tum",
                false, "", "IN.graph", cmd);
            TCLAP::ValueArg<std::string> argAps(
                "a", "aps",
                "AP map (YAML): known AP poses (fixed), or names/arrays with "
                "--estimate-aps",
                false, "", "APS.yaml", cmd);
            TCLAP::SwitchArg argEstimate(
                "", "estimate-aps", "Treat the APs as unknown: estimate their poses", cmd);
            TCLAP::ValueArg<std::string> argPose(
                "", "sensor-pose",
                "Receive array on the robot for CSV bearings: x y z yaw pitch roll (m, deg)", false,
                "0 0 0 0 0 0", "x y z yaw pitch roll", cmd);
            TCLAP::ValueArg<std::string> argGt(
                "g", "ground-truth-tum", "True trajectory (TUM) for the ATE", false, "", "GT.txt",
                cmd);
            TCLAP::ValueArg<std::string> argTrueAps(
                "", "true-aps", "True AP poses (YAML), for AP errors with --estimate-aps", false,
                "", "TX.yaml", cmd);
            TCLAP::ValueArg<double> argPeriod(
                "", "node-period", "A pose node every S seconds of odometry", false, 0.5, "S", cmd);
            TCLAP::ValueArg<double> argOdoXY(
                "", "odo-sigma-xy", "Odometry noise [m per sqrt(m)]", false, 0.02, "K", cmd);
            TCLAP::ValueArg<double> argOdoYaw(
                "", "odo-sigma-yaw", "Odometry heading noise [deg per sqrt(m)]", false, 1.0, "K",
                cmd);
            TCLAP::ValueArg<double> argScaleStd(
                "", "odo-scale-std",
                "Odometry scale error, sigma (0.02 = 2 %): estimated with this prior (0 with "
                "--odo-yaw-drift-std 0: the odometry has no systematic error)",
                false, 0.02, "S", cmd);
            TCLAP::ValueArg<double> argYawDriftStd(
                "", "odo-yaw-drift-std",
                "Odometry heading drift, sigma [deg per m travelled]: estimated with this prior",
                false, 0.3, "DEG", cmd);
            TCLAP::ValueArg<double> argDecorrelation(
                "", "decorrelation",
                "Bearings received within a cell of this size [m] share their multipath error: "
                "per AP they weigh as one bearing per cell visited; 0: every bearing independent",
                false, 0.5, "M", cmd);
            TCLAP::ValueArg<double> argMinStd(
                "", "min-std", "Floor on bearing sigma [deg]", false, 3.0, "DEG", cmd);
            TCLAP::ValueArg<std::string> argLoss(
                "", "loss", "Robust loss of bearing edges: cauchy|huber|none", false, "cauchy",
                "NAME", cmd);
            TCLAP::ValueArg<double> argLossScale(
                "", "loss-scale", "Robust loss scale [sigmas]", false, 1.0, "K", cmd);
            TCLAP::ValueArg<int> argMaxIter(
                "", "max-iterations",
                "Ceres iterations per solve; a solve stopped by this limit is reported as not "
                "converged",
                false, 500, "N", cmd);
            TCLAP::ValueArg<double> argGrowth(
                "", "growth-window",
                "Estimated APs: also start from a solution grown S seconds at a time (robust to "
                "strong odometry drift); 0 = start from the odometry only",
                false, 30, "S", cmd);
            TCLAP::SwitchArg argNoAoa("", "no-aoa", "Don't use AoA", cmd);
            TCLAP::SwitchArg argNoAod("", "no-aod", "Don't use AoD", cmd);
            TCLAP::ValueArg<std::string> argOut(
                "o", "out-dir", "Output folder", false, "wifi-graphslam-out", "DIR", cmd);
            TCLAP::SwitchArg argNoPlots("", "no-plots", "Don't draw PNGs", cmd);
            TCLAP::SwitchArg argVerbose("v", "verbose", "Ceres progress", cmd);
            TCLAP::ValueArg<std::string> argMcap(
                "", "mcap", mcap_output::optionHelp(), false, "", "OUT.mcap", cmd);

            cli::JoinedArgv args(argc, argv, "--sensor-pose", 6);
            if (const int rc = cli::parseCommandLine(cmd, args.argc(), args.argv()); rc >= 0)
                return rc;
            const std::string outDir = argOut.getValue();
            mrpt::system::createDirectory(outDir);

            GraphSlamInput in;
            GraphSlamOptions opt;
            if (argAps.isSet()) in.aps = TransmitterMap::fromYamlFile(argAps.getValue());
            opt.apsKnown = argAps.isSet() && !argEstimate.getValue();
            InputWarnings csvWarn;
            if (argRawlog.isSet() == argCsv.isSet())
                throw std::invalid_argument("give exactly one of --rawlog and --bearings-csv");
            if (argRawlog.isSet())
            {
                auto c = readRawlog(argRawlog.getValue());
                in.bearings = std::move(c.bearings);
                in.odometry = std::move(c.odometry);
            }
            else
            {
                BearingCsvOptions co;
                const auto sp = cli::poseFromText(argPose.getValue(), "--sensor-pose");
                co.sensorPose = mrpt::math::TPose2D(sp.x(), sp.y(), sp.yaw());
                co.names = &in.aps;
                in.bearings = readBearingCsv(argCsv.getValue(), co, &csvWarn);
                std::cerr << csvWarn.csvWarning(argCsv.getValue());
            }
            if (argOdo.isSet()) in.odometry = Trajectory2D::fromTumFile(argOdo.getValue());
            mrpt::graphs::CNetworkOfPoses2DInf graph;
            if (argGraph.isSet())
            {
                if (!argOdo.isSet())
                    throw std::invalid_argument("--graph needs --odometry-tum for node times");
                graph.loadFromTextFile(argGraph.getValue());
                in.graph = &graph;
            }
            if (in.odometry.empty())
                throw std::runtime_error(
                    "no odometry: give --odometry-tum or a rawlog with "
                    "CObservationOdometry");
            opt.nodePeriod_s = argPeriod.getValue();
            opt.odoSigmaXY_perSqrtM = argOdoXY.getValue();
            opt.odoSigmaYaw_perSqrtM = mrpt::DEG2RAD(argOdoYaw.getValue());
            if (argScaleStd.getValue() < 0 || argYawDriftStd.getValue() < 0 ||
                argDecorrelation.getValue() < 0)
                throw std::invalid_argument(
                    "--odo-scale-std, --odo-yaw-drift-std and --decorrelation must be >= 0");
            opt.odoScaleStd = argScaleStd.getValue();
            opt.odoYawDriftStd_radPerM = mrpt::DEG2RAD(argYawDriftStd.getValue());
            opt.bearingDecorrelation_m = argDecorrelation.getValue();
            opt.minStd_rad = mrpt::DEG2RAD(argMinStd.getValue());
            opt.loss = argLoss.getValue();
            opt.lossScale = argLossScale.getValue();
            opt.useAoa = !argNoAoa.getValue();
            opt.useAod = !argNoAod.getValue();
            opt.verbose = argVerbose.getValue();
            opt.maxIterations = argMaxIter.getValue();
            opt.growthWindow_s = argGrowth.getValue();
            if (opt.maxIterations < 1) throw std::invalid_argument("--max-iterations must be >= 1");
            if (opt.growthWindow_s < 0) throw std::invalid_argument("--growth-window must be >= 0");

            std::cerr << "wifi-graphslam: " << in.bearings.size() << " bearings, "
                      << in.odometry.size() << " odometry poses, APs "
                      << (opt.apsKnown ? "known" : "estimated") << "; solving...\n";
            opt.progress = [](const std::string& line) { std::cerr << "  " << line << "\n"; };
            auto res = solveBearingGraph(in, opt);
            res.warnings.noAngle += csvWarn.noAngle;

            res.graph.saveToTextFile(outDir + "/solution.graph");
            res.poses.saveTum(outDir + "/trajectory_tum.txt", "wifi-graphslam solution");
            res.initialPoses.saveTum(
                outDir + "/odometry_nodes_tum.txt", "odometry at the graph nodes (initial guess)");
            std::ofstream(outDir + "/aps.yaml")
                << "# APs after wifi-graphslam (" << (opt.apsKnown ? "fixed" : "estimated") << ")\n"
                << res.aps.asYamlText();
            if (argMcap.isSet())
                mcap_output::writeTrajectory(
                    argMcap.getValue(), res.poses, nullptr, in.bearings, &res.aps, nullptr,
                    !opt.apsKnown && res.apCov.size() == res.aps.size() ? &res.apCov : nullptr);

            std::ostringstream sum;
            sum << "wifi-graphslam summary\n"
                << "  graph     : " << res.poses.size() << " poses, " << res.aps.size() << " APs, "
                << res.odometryEdges << " odometry + " << res.aoaEdges << " AoA + " << res.aodEdges
                << " AoD edges\n"
                << "  warnings  : " << res.warnings.summary() << "; " << res.apsWithoutBearings
                << " APs without bearings\n"
                << "  solver    : " << res.solverReport << "\n";
            sum << "  start     : " << res.placement << " (lowest final cost of " << res.hypotheses
                << " optimised starts)\n";
            if (opt.odoScaleStd > 0 || opt.odoYawDriftStd_radPerM > 0)
            {
                char b[160];
                std::snprintf(
                    b, sizeof(b),
                    "  odometry  : scale x%.4f, heading drift %+.3f deg/m (estimated; priors "
                    "%.3f, %.2f deg/m)\n",
                    res.odometryScale, mrpt::RAD2DEG(res.odometryYawDrift_radPerM), opt.odoScaleStd,
                    mrpt::RAD2DEG(opt.odoYawDriftStd_radPerM));
                sum << b;
            }
            // Bearings are angles: scaling the trajectory and unknown APs together changes none,
            // so only the odometry (and its scale prior) sets the scale.
            if (!opt.apsKnown)
                sum << "  scale     : with estimated APs no bearing observes it: the map keeps the "
                       "odometry's scale error\n";
            if (!res.converged)
            {
                const std::string warn =
                    "  WARNING   : Ceres did not converge (" + std::to_string(res.iterations) +
                    " iterations): the trajectory may be far from the optimum; raise "
                    "--max-iterations or check the bearings and the odometry noise\n";
                sum << warn;
                std::cerr << "wifi-graphslam:" << warn.substr(1);
            }
            {
                char buf[256];
                std::snprintf(
                    buf, sizeof(buf),
                    "  bearings  : median residual %.1f deg (%.2f sigma), %.0f %% within 3 "
                    "sigma of the solution\n",
                    res.medianResidual_deg, res.medianWhitenedResidual,
                    100 * res.bearingsWithin3Sigma);
                sum << buf;
                // A calibrated receiver leaves a few degrees (1-3 on the simulator); tens of
                // degrees are biased bearings, which no start or robust loss can fix.
                if (res.medianResidual_deg > 10)
                    sum << "  WARNING   : the bearings disagree with the solution by a median of "
                           "more than 10 deg: they are biased (a receiver calibration of another "
                           "boot or simulator seed? antenna jumps?); check the calibration "
                           "(wifi-calibrate --check) before trusting this trajectory\n";
            }
            sum << "  time      : solve " << res.solveTime_s << " s, total " << res.totalTime_s
                << " s\n";
            {
                // Where the time went (own stream: fixed notation would stick to `sum`).
                std::ostringstream phases;
                phases << std::fixed << std::setprecision(2);
                for (size_t i = 0; i < res.phases.size(); ++i)
                    phases << (i ? ", " : " ") << res.phases[i].name << " " << res.phases[i].seconds
                           << " s";
                sum << "  phases    :" << phases.str();
            }
            sum << "; " << res.apTriangulations << " AP triangulations\n";
            if (argGt.isSet())
            {
                const auto gt = Trajectory2D::fromTumFile(argGt.getValue());
                const auto ate = absoluteTrajectoryError(res.poses, gt, true);
                const auto ateOdo = absoluteTrajectoryError(res.initialPoses, gt, true);
                const double red = 100 * (1 - ate.stats.median / ateOdo.stats.median);
                char buf[128];
                std::snprintf(buf, sizeof(buf), "%.1f %%", red);
                sum << "  ATE odometry only (SE(2)-aligned): " << ateOdo.stats.asString() << "\n"
                    << "  ATE WiFi graph SLAM (SE(2)-aligned): " << ate.stats.asString() << "\n"
                    << "  median ATE reduction: " << buf
                    << "  (target >= 50 %, WiROS 30 %): " << (red >= 50 ? "MET" : "NOT MET")
                    << "\n";
                if (!opt.apsKnown)
                {
                    // The error left when the unobservable scale is taken out (evo's
                    // --correct_scale): what the bearings corrected.
                    const auto simSlam = absoluteTrajectoryError(res.poses, gt, true, true);
                    const auto simOdo = absoluteTrajectoryError(res.initialPoses, gt, true, true);
                    std::snprintf(
                        buf, sizeof(buf), "%.1f %%",
                        100 * (1 - simSlam.stats.median / simOdo.stats.median));
                    sum << "  ATE odometry only (Sim(2)-aligned, scale x" << simOdo.scale
                        << "): " << simOdo.stats.asString() << "\n"
                        << "  ATE WiFi graph SLAM (Sim(2)-aligned, scale x" << simSlam.scale
                        << "): " << simSlam.stats.asString() << "\n"
                        << "  median ATE reduction without the scale: " << buf << "\n";
                }
                if (!argNoPlots.getValue())
                {
                    plot::Figure f;
                    f.title = "wifi-graphslam: trajectories (aligned to ground truth)";
                    f.xlabel = "x [m]", f.ylabel = "y [m]", f.equalAxes = true;
                    auto series = [&](const Trajectory2D& tr, const mrpt::math::TPose2D& T,
                                      const std::string& title, const std::string& style)
                    {
                        plot::Series s{title, {}, {}, style};
                        const double c = std::cos(T.phi), sn = std::sin(T.phi);
                        for (const auto& p : tr.poses)
                            s.x.push_back(T.x + c * p.x - sn * p.y),
                                s.y.push_back(T.y + sn * p.x + c * p.y);
                        return s;
                    };
                    f.series.push_back(
                        series(gt, {0, 0, 0}, "ground truth", "lines lw 3 lc rgb '#333333'"));
                    f.series.push_back(series(
                        res.initialPoses, ateOdo.alignment, "odometry",
                        "lines lw 1 lc rgb '#ff7f0e'"));
                    f.series.push_back(series(
                        res.poses, ate.alignment, "WiFi graph SLAM",
                        "lines lw 1.5 lc rgb '#d62728'"));
                    plot::Series aps{"APs", {}, {}, "points pt 5 ps 2 lc rgb '#1f77b4'"};
                    const double c = std::cos(ate.alignment.phi), sn = std::sin(ate.alignment.phi);
                    for (const auto& t : res.aps.transmitters())
                        aps.x.push_back(ate.alignment.x + c * t.pose.x - sn * t.pose.y),
                            aps.y.push_back(ate.alignment.y + sn * t.pose.x + c * t.pose.y);
                    f.series.push_back(aps);
                    std::string err;
                    if (!plot::savePng(f, outDir + "/trajectory.png", &err))
                        std::cerr << "warning: " << err << "\n";
                    plot::Figure cdf;
                    cdf.title = "Absolute trajectory error CDF (SE(2)-aligned)";
                    cdf.xlabel = "ATE [m]", cdf.ylabel = "fraction";
                    cdf.series = {
                        plot::cdf(ateOdo.errors, "odometry only"),
                        plot::cdf(ate.errors, "WiFi graph SLAM")};
                    plot::savePng(cdf, outDir + "/ate_cdf.png", &err);
                }
            }
            if (argTrueAps.isSet() && !opt.apsKnown)
            {
                const auto truth = TransmitterMap::fromYamlFile(argTrueAps.getValue());
                // APs live in the odometry frame: compare after the trajectory's alignment.
                if (argGt.isSet())
                {
                    const auto gt = Trajectory2D::fromTumFile(argGt.getValue());
                    const auto T = absoluteTrajectoryError(res.poses, gt, true).alignment;
                    const double c = std::cos(T.phi), s = std::sin(T.phi);
                    for (const auto& t : res.aps.transmitters())
                        if (const auto* k = truth.find(t.mac))
                        {
                            const double x = T.x + c * t.pose.x - s * t.pose.y;
                            const double y = T.y + s * t.pose.x + c * t.pose.y;
                            sum << "  AP " << t.name << ": error "
                                << std::hypot(x - k->pose.x, y - k->pose.y) << " m\n";
                        }
                }
            }
            std::cout << sum.str();
            std::ofstream(outDir + "/summary.txt") << sum.str();
            return 0;
        });
}
