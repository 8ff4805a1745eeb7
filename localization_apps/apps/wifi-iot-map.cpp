/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-iot-map: localizes unknown WiFi transmitters (IoT devices) from the robot's AoA bearings
 * along a known trajectory: robust, mirror-aware triangulation with uncertainty ellipses;
 * writes a device map (CSV + YAML) and a PNG. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/BearingGraphSlam.h>
#include <mrpt_wifi/localization/DeviceMapper.h>
#include <mrpt_wifi/localization/Plot.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/obs/CommandLine.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>

#include "McapOutput.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

int main(int argc, char** argv)
{
    return cli::runMain(
        "wifi-iot-map",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Maps WiFi devices from the robot's AoA bearings along its trajectory: robust "
                "triangulation (mirror-aware), uncertainty ellipses, device map (CSV/YAML) and "
                "PNG.",
                ' ', "0.1");
            TCLAP::ValueArg<std::string> argRawlog(
                "r", "rawlog", "Rawlog with CObservationWiFiBearing (+ odometry)", false, "",
                "IN.rawlog", cmd);
            TCLAP::ValueArg<std::string> argCsv(
                "b", "bearings-csv", "Bearings CSV (see share/localization/README.md)", false, "",
                "B.csv", cmd);
            TCLAP::ValueArg<std::string> argTraj(
                "t", "trajectory",
                "Robot trajectory (TUM) in the map frame, trusted as exact (e.g. from a "
                "localization system). Without it, odometry (--odometry-tum or the rawlog's) is "
                "used jointly: devices and trajectory are estimated together",
                false, "", "TRAJ.txt", cmd);
            TCLAP::ValueArg<std::string> argOdo(
                "", "odometry-tum",
                "Odometry (TUM), which drifts: devices and trajectory are estimated jointly "
                "(bearing-only graph SLAM with unknown transmitters, Ceres); device sigmas come "
                "from the joint solution",
                false, "", "ODO.txt", cmd);
            TCLAP::ValueArg<std::string> argInit(
                "", "initial-pose",
                "With odometry: the robot's pose at the odometry's first reading in the map frame "
                "'x y yaw_deg' (default: the odometry frame)",
                false, "0 0 0", "x y yaw", cmd);
            TCLAP::ValueArg<double> argOdoSigma(
                "", "odometry-sigma",
                "With odometry: its position noise [m per sqrt(m) travelled] (yaw: 1 deg per "
                "sqrt(m) times this / 0.02)",
                false, 0.02, "S", cmd);
            TCLAP::ValueArg<double> argScaleStd(
                "", "odometry-scale-std",
                "With odometry estimated jointly: sigma of its scale error (0.02 = 2 %); the "
                "scale is estimated with this prior and its uncertainty enters the devices' "
                "sigma (bearings alone cannot tell the scale)",
                false, 0.02, "S", cmd);
            TCLAP::ValueArg<double> argYawDriftStd(
                "", "odometry-yaw-drift-std",
                "With odometry estimated jointly: sigma of its heading drift [deg per m "
                "travelled], estimated with this prior",
                false, 0.3, "DEG", cmd);
            TCLAP::ValueArg<double> argDecorrelation(
                "", "decorrelation",
                "Bearings received within a cell of this size [m] share their multipath error: "
                "per device they count as one bearing per cell visited (the joint solution's "
                "weights and the sigmas of the triangulation); 0: every bearing independent",
                false, 0.5, "M", cmd);
            TCLAP::ValueArg<std::string> argDrift(
                "", "odometry-drift",
                "With --trust-odometry: the odometry's drift 'XY YAW' (position m per sqrt(m) "
                "travelled, heading deg per sqrt(m)); the devices' sigma includes the pose "
                "uncertainty it gives the rays ('0 0': the odometry is exact)",
                false, "0.01 0.3", "XY YAW", cmd);
            TCLAP::SwitchArg argTrustOdometry(
                "", "trust-odometry",
                "Take the odometry (--odometry-tum or the rawlog's) as the exact trajectory "
                "instead of estimating it jointly, as wifi-localize's live device map does",
                cmd);
            TCLAP::ValueArg<std::string> argPose(
                "", "sensor-pose",
                "Receive array on the robot for CSV bearings: x y z yaw pitch roll (m, deg)", false,
                "0 0 0 0 0 0", "x y z yaw pitch roll", cmd);
            TCLAP::ValueArg<std::string> argTruth(
                "", "truth", "True device positions (transmitters YAML) for errors", false, "",
                "TX.yaml", cmd);
            TCLAP::ValueArg<std::string> argOnly(
                "", "devices", "Comma-separated MACs to map (default: every transmitter seen)",
                false, "", "MACS", cmd);
            TCLAP::ValueArg<std::string> argBounds(
                "", "bounds", "Search area 'xmin xmax ymin ymax' [m] (default: trajectory +- 2 m)",
                false, "", "BOUNDS", cmd);
            TCLAP::ValueArg<double> argMinStd(
                "", "min-std", "Floor on bearing sigma [deg]", false, 3.0, "DEG", cmd);
            TCLAP::ValueArg<double> argOutl(
                "", "outlier-prob", "Outlier weight of the robust model", false, 0.1, "P", cmd);
            TCLAP::ValueArg<std::string> argLoss(
                "", "loss", "Robust loss of the refinement: cauchy|huber|none", false, "cauchy",
                "NAME", cmd);
            TCLAP::ValueArg<double> argGrid(
                "", "grid", "Global search grid step [m]", false, 0.1, "M", cmd);
            TCLAP::ValueArg<std::string> argOut(
                "o", "out-dir", "Output folder", false, "wifi-iot-out", "DIR", cmd);
            TCLAP::SwitchArg argNoPlots("", "no-plots", "Don't draw PNGs", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress display", cmd);
            TCLAP::ValueArg<std::string> argMcap(
                "", "mcap", mcap_output::optionHelp(), false, "", "OUT.mcap", cmd);

            cli::JoinedArgv joined(argc, argv, "--sensor-pose", 6);
            cli::JoinedArgv args(
                joined.argc(), const_cast<char**>(joined.argv()), "--initial-pose", 3);
            if (const int rc = cli::parseCommandLine(cmd, args.argc(), args.argv()); rc >= 0)
                return rc;
            const std::string outDir = argOut.getValue();
            mrpt::system::createDirectory(outDir);

            TransmitterMap truth;
            if (argTruth.isSet()) truth = TransmitterMap::fromYamlFile(argTruth.getValue());

            std::vector<BearingRecord> bearings;
            Trajectory2D traj;
            InputWarnings warn;
            if (argCsv.isSet() == argRawlog.isSet())
                throw std::invalid_argument("give exactly one of --bearings-csv and --rawlog");
            if (argCsv.isSet())
            {
                BearingCsvOptions co;
                const auto sp = cli::poseFromText(argPose.getValue(), "--sensor-pose");
                co.sensorPose = mrpt::math::TPose2D(sp.x(), sp.y(), sp.yaw());
                co.names = argTruth.isSet() ? &truth : nullptr;
                bearings = readBearingCsv(argCsv.getValue(), co, &warn);
                std::cerr << warn.csvWarning(argCsv.getValue());
            }
            Trajectory2D odo;
            if (argRawlog.isSet())
            {
                auto c = readRawlog(argRawlog.getValue());
                bearings = std::move(c.bearings);
                odo = std::move(c.odometry);
            }
            if (argTraj.isSet() && argOdo.isSet())
                throw std::invalid_argument("give --trajectory or --odometry-tum, not both");
            if (argOdo.isSet()) odo = Trajectory2D::fromTumFile(argOdo.getValue());
            if (argTraj.isSet()) traj = Trajectory2D::fromTumFile(argTraj.getValue());
            if (traj.empty() && odo.empty())
                throw std::runtime_error(
                    "no trajectory: give --trajectory, --odometry-tum or a rawlog with odometry");
            // Without --initial-pose the odometry's own frame is the map frame.
            if (!odo.empty() && argInit.isSet())
            {
                // Odometry re-anchored at --initial-pose: T ⊕ (odo₀⁻¹ ⊕ odo_k).
                std::istringstream is(argInit.getValue());
                double x0, y0, yaw0;
                if (!(is >> x0 >> y0 >> yaw0))
                    throw std::invalid_argument("--initial-pose: expected 'x y yaw_deg'");
                const mrpt::poses::CPose2D T(x0, y0, mrpt::DEG2RAD(yaw0));
                const mrpt::poses::CPose2D o0(odo.poses.front());
                for (auto& p : odo.poses) p = (T + (mrpt::poses::CPose2D(p) - o0)).asTPose();
            }
            if (traj.empty() && argTrustOdometry.getValue()) traj = odo;
            const bool joint = traj.empty() && !odo.empty();
            if (bearings.empty()) throw std::runtime_error("the input holds no bearings");

            std::set<MacAddress> only;
            if (argOnly.isSet())
            {
                std::stringstream ss(argOnly.getValue());
                std::string m;
                while (std::getline(ss, m, ',')) only.insert(MacAddress::fromString(m));
            }
            if (!only.empty())
            {
                std::vector<BearingRecord> kept;
                for (const auto& b : bearings)
                    if (only.count(b.transmitter)) kept.push_back(b);
                bearings = std::move(kept);
            }
            GraphSlamResult jointRes;
            if (joint)
            {
                // Bearing-only SLAM with unknown transmitters: the devices are the graph's APs.
                GraphSlamInput in;
                in.odometry = odo;
                in.bearings = bearings;
                GraphSlamOptions go;
                go.useAod = false;
                go.apCovariance = true;
                go.minStd_rad = mrpt::DEG2RAD(argMinStd.getValue());
                go.loss = argLoss.getValue();
                go.odoSigmaXY_perSqrtM = argOdoSigma.getValue();
                go.odoSigmaYaw_perSqrtM = 0.0175 * argOdoSigma.getValue() / 0.02;
                if (argScaleStd.getValue() < 0 || argYawDriftStd.getValue() < 0)
                    throw std::invalid_argument(
                        "--odometry-scale-std and --odometry-yaw-drift-std must be >= 0");
                go.bearingDecorrelation_m = argDecorrelation.getValue();
                go.odoScaleStd = argScaleStd.getValue();
                go.odoYawDriftStd_radPerM = mrpt::DEG2RAD(argYawDriftStd.getValue());
                if (!argQuiet.getValue())
                    std::cerr << "wifi-iot-map: " << bearings.size() << " bearings on "
                              << odo.size()
                              << " odometry poses: devices and trajectory jointly...\n";
                if (!argQuiet.getValue())
                    go.progress = [](const std::string& line)
                    { std::cerr << "  " << line << "\n"; };
                jointRes = solveBearingGraph(in, go);
                traj = jointRes.poses;
                jointRes.poses.saveTum(
                    outDir + "/trajectory_tum.txt", "wifi-iot-map: trajectory (joint solution)");
            }
            auto rays = raysFromBearings(bearings, traj, &warn);
            if (rays.empty())
                throw std::runtime_error(
                    "no bearing falls within the trajectory's time span (" + warn.summary() + ")");
            const bool trustedOdometry = !joint && !argTraj.isSet();
            if (trustedOdometry)
            {
                std::istringstream is(argDrift.getValue());
                OdometryDrift drift;
                double yaw_deg = 0;
                if (!(is >> drift.sigmaXY_perSqrtM >> yaw_deg) || drift.sigmaXY_perSqrtM < 0 ||
                    yaw_deg < 0)
                    throw std::invalid_argument(
                        "--odometry-drift: expected 'XY YAW' (two numbers >= 0)");
                drift.sigmaYaw_perSqrtM = mrpt::DEG2RAD(yaw_deg);
                addOdometryDrift(rays, traj, drift);
            }

            DeviceMapOptions o;
            o.model.minStd_rad = mrpt::DEG2RAD(argMinStd.getValue());
            o.model.outlierProb = argOutl.getValue();
            o.loss = argLoss.getValue();
            o.gridStep_m = argGrid.getValue();
            if (argDecorrelation.getValue() < 0)
                throw std::invalid_argument("--decorrelation: expected a size >= 0 [m]");
            o.decorrelation_m = argDecorrelation.getValue();
            if (argBounds.isSet())
            {
                std::istringstream is(argBounds.getValue());
                if (!(is >> o.xmin >> o.xmax >> o.ymin >> o.ymax) || o.xmin >= o.xmax ||
                    o.ymin >= o.ymax)
                    throw std::invalid_argument("--bounds: expected 'xmin xmax ymin ymax'");
                o.boundsGiven = true;
            }

            cli::Progress progress("wifi-iot-map", !argQuiet.getValue());
            std::vector<DeviceEstimate> devs;
            size_t k = 0;
            for (const auto& [mac, r] : rays)
            {
                progress.update(double(k++) / rays.size(), mac.asString());
                if (!only.empty() && !only.count(mac)) continue;
                auto d = triangulateDevice(r, o);
                d.mac = mac;
                if (joint)
                {
                    // The joint solution's device and its covariance (the rays above, on the
                    // solved trajectory, only give the residual statistics).
                    const auto& aps = jointRes.aps.transmitters();
                    const auto it = std::find_if(
                        aps.begin(), aps.end(), [&](const auto& t) { return t.mac == mac; });
                    if (it == aps.end())
                    {
                        d.localized = false;
                        d.note = "not in the joint solution (no usable AoA)";
                    }
                    else
                    {
                        const auto& c = jointRes.apCov[size_t(it - aps.begin())];
                        d.x = it->pose.x, d.y = it->pose.y;
                        // The joint covariance: decorrelated bearings, the trajectory and the
                        // odometry's scale and heading drift marginalised.
                        d.cov[0] = c[0], d.cov[1] = c[1], d.cov[2] = c[2];
                        d.covInflation = 1;
                        d.localized = jointRes.apCovarianceOk && d.rays >= o.minRays;
                        if (!jointRes.apCovarianceOk) d.note = "joint covariance rank deficient";
                    }
                }
                if (const auto* t = truth.find(mac)) d.name = t->name;
                devs.push_back(d);
            }
            progress.done(std::to_string(devs.size()) + " devices");
            saveDeviceCsv(outDir + "/devices.csv", devs);
            saveDeviceYaml(outDir + "/devices.yaml", devs);
            if (argMcap.isSet())
            {
                // Rays end at the device they measure.
                TransmitterMap deviceMap;
                const auto devices = mcap_output::devicesOf(devs, &deviceMap);
                mcap_output::writeTrajectory(
                    argMcap.getValue(), traj, nullptr, bearings, nullptr, &devices, nullptr,
                    &deviceMap);
            }

            std::ostringstream sum;
            sum << "wifi-iot-map summary\n  input   : " << bearings.size() << " bearings, "
                << traj.size()
                << (joint ? " poses estimated jointly from odometry (" + jointRes.solverReport + ")"
                          : " trajectory poses (trusted)")
                << "\n  warnings: " << warn.summary() << "\n";
            std::vector<double> errs;
            size_t insideEllipse = 0;
            char buf[512];
            for (const auto& d : devs)
            {
                const double sx = std::sqrt(std::max(0.0, d.cov[0]));
                const double sy = std::sqrt(std::max(0.0, d.cov[2]));
                std::snprintf(
                    buf, sizeof(buf),
                    "  %s %-12s %s x=%6.2f y=%6.2f  sigma=(%.2f, %.2f) m  bearings=%zu inliers=%zu "
                    "median residual=%.1f deg",
                    d.mac.asString().c_str(), d.name.c_str(), d.localized ? "OK " : "-- ", d.x, d.y,
                    sx, sy, d.rays, d.inliers, d.medianResidual_deg);
                sum << buf;
                if (const auto* t = truth.find(d.mac); t && d.localized)
                {
                    const double ex = d.x - t->pose.x, ey = d.y - t->pose.y;
                    errs.push_back(std::hypot(ex, ey));
                    const bool inside =
                        mahalanobis2(d.cov[0], d.cov[1], d.cov[2], ex, ey) <= kChi2TwoDof95;
                    insideEllipse += inside;
                    std::snprintf(
                        buf, sizeof(buf), "  error=%.2f m (%s its 95 %% ellipse)", errs.back(),
                        inside ? "inside" : "OUTSIDE");
                    sum << buf;
                }
                if (!d.note.empty()) sum << "  (" << d.note << ")";
                sum << "\n";
            }
            if (argTruth.isSet())
            {
                size_t missing = 0;
                for (const auto& t : truth.transmitters())
                {
                    bool found = false;
                    for (const auto& d : devs) found |= (d.mac == t.mac && d.localized);
                    if (!found) ++missing;
                }
                const auto st = computeStats(errs);
                sum << "  device error: " << st.asString() << "; " << missing
                    << " true devices not localized\n"
                    << "  inside their 95 % ellipse: " << insideEllipse << " of " << truth.size()
                    << " true devices\n"
                    << "  target: median device error <= 0.5 m (WiROS: within 2 m): "
                    << (errs.size() && missing == 0 && st.median <= 0.5 ? "MET" : "NOT MET")
                    << "\n";
            }
            std::cout << sum.str();
            std::ofstream(outDir + "/summary.txt") << sum.str();

            if (!argNoPlots.getValue())
            {
                plot::Figure f;
                f.title = "wifi-iot-map: devices (95% ellipses)";
                f.xlabel = "x [m]", f.ylabel = "y [m]", f.equalAxes = true;
                plot::Series tr{"robot trajectory", {}, {}, "lines lw 1 lc rgb '#999999'"};
                for (const auto& p : traj.poses) tr.x.push_back(p.x), tr.y.push_back(p.y);
                f.series.push_back(tr);
                plot::Series est{"estimate", {}, {}, "points pt 7 ps 1.5 lc rgb '#d62728'"};
                for (const auto& d : devs)
                {
                    if (!d.localized) continue;
                    est.x.push_back(d.x), est.y.push_back(d.y);
                    f.series.push_back(plot::ellipse(
                        d.x, d.y, d.cov[0], d.cov[1], d.cov[2], std::sqrt(kChi2TwoDof95), "",
                        "lines lw 1 lc rgb '#d62728'"));
                    f.extra.push_back(
                        "set label '" + (d.name.empty() ? d.mac.asString() : d.name) + "' at " +
                        std::to_string(d.x) + "," + std::to_string(d.y) + " offset 1,1");
                }
                f.series.push_back(est);
                if (argTruth.isSet())
                {
                    plot::Series t{
                        "true position", {}, {}, "points pt 4 ps 2 lw 2 lc rgb '#1f77b4'"};
                    for (const auto& x : truth.transmitters())
                        t.x.push_back(x.pose.x), t.y.push_back(x.pose.y);
                    f.series.push_back(t);
                }
                std::string err;
                if (!plot::savePng(f, outDir + "/device_map.png", &err))
                    std::cerr << "warning: " << err << "\n";
                if (!errs.empty())
                {
                    plot::Figure c;
                    c.title = "Device position error CDF";
                    c.xlabel = "error [m]", c.ylabel = "fraction";
                    c.series = {plot::cdf(errs, "wifi-iot-map")};
                    c.extra.push_back("set xrange [0:2.2<*]\nset yrange [0:1.05]");
                    c.extra.push_back(
                        "set arrow from 2, graph 0 to 2, graph 1 nohead dt 2\n"
                        "set label 'WiROS: within 2 m' at 2, graph 0.5 offset -12,0");
                    plot::savePng(c, outDir + "/error_cdf.png", &err);
                }
            }
            return 0;
        });
}
