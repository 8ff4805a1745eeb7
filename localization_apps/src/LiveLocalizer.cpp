/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/Clock.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/localization/UnknownMotion.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mrpt_wifi::localization
{
mrpt::obs::CActionRobotMovement2D unknownMotionAction(
    double dt_s, double maxSpeed_mps, double maxTurnRate_rps)
{
    // UnknownMotion's random walk (no constant-velocity prediction) with a 1 s horizon.
    UnknownMotion m;
    m.maxSpeed_mps = maxSpeed_mps;
    m.maxTurnRate_dps = mrpt::RAD2DEG(maxTurnRate_rps);
    m.correlationTime_s = 1.0;
    m.maxStep_s = 5.0;
    m.minStdXY_m = m.minStdPhi_deg = 0;
    m.constantVelocity = false;
    return *m.makeAction(std::max(dt_s, 1e-4));
}

void LiveLocalizerOptions::loadFromConfigFile(
    const mrpt::config::CConfigFileBase& c, const std::string& s)
{
    unknownMotionSpeed_mps = c.read_double(s, "unknown_motion_speed_mps", unknownMotionSpeed_mps);
    unknownMotionTurn_rps = mrpt::DEG2RAD(
        c.read_double(s, "unknown_motion_turn_dps", mrpt::RAD2DEG(unknownMotionTurn_rps)));
    const int maxPerStep = c.read_int(s, "max_bearings_per_step", int(maxBearingsPerStep));
    if (!(unknownMotionSpeed_mps > 0) || !(unknownMotionTurn_rps > 0) || maxPerStep < 0)
        throw std::invalid_argument(
            "[" + s +
            "] unknown_motion_speed_mps and unknown_motion_turn_dps must be > 0, "
            "max_bearings_per_step >= 0");
    maxBearingsPerStep = size_t(maxPerStep);
}

LiveLocalizer::LiveLocalizer(const mrpt::config::CConfigFileBase& ini, const std::string& iniDir)
{
    opts_.loadFromConfigFile(ini, "wifi-localize");

    // The map, as wifi-pf-localization builds it (relative transmitters_file: cwd, then iniDir).
    const std::string mapSect = "MetricMap_wifiBearingMap_00_creationOpts";
    mrpt::maps::TSetOfMetricMapInitializers inits;
    inits.loadFromConfigFile(ini, "MetricMap");
    for (auto& i : inits)
        if (auto* w = dynamic_cast<CWiFiBearingMap::TMapDefinition*>(i.get()))
        {
            auto& f = w->transmittersFile;
            if (!f.empty() && f[0] != '/' && !mrpt::system::fileExists(f) &&
                mrpt::system::fileExists(iniDir + "/" + f))
                f = iniDir + "/" + f;
        }
    map_->setListOfMaps(inits);
    wifiMap_ = map_->mapByClass<CWiFiBearingMap>();
    if (!wifiMap_)
        throw std::runtime_error(
            "the [MetricMap] section creates no wifiBearingMap (wifiBearingMap_count=1 missing?)");
    if (wifiMap_->transmitters().empty())
        throw std::runtime_error(
            "the WiFi map has no transmitters: set transmitters_file in [" + mapSect + "]");

    const std::string sect = "LocalizationExperiment";
    const int n = ini.read_int(sect, "particles_count", 0, true);
    if (n <= 0) throw std::invalid_argument("[LocalizationExperiment] particles_count must be > 0");
    if (ini.read_int(sect, "init_PDF_mode", 1) != 1)
        throw std::invalid_argument(
            "[LocalizationExperiment] init_PDF_mode: wifi-localize needs 1 (uniform in the "
            "init_PDF_min/max_* box)");
    const auto rd = [&](const char* k) { return ini.read_double(sect, k, 0, true); };
    pdf_.resetUniform(
        rd("init_PDF_min_x"), rd("init_PDF_max_x"), rd("init_PDF_min_y"), rd("init_PDF_max_y"),
        mrpt::DEG2RAD(ini.read_double(sect, "init_PDF_min_yaw_deg", -180)),
        mrpt::DEG2RAD(ini.read_double(sect, "init_PDF_max_yaw_deg", 180)), size_t(n));
    pdf_.options.metricMap = map_;
    pdf_.options.KLD_params.loadFromConfigFile(ini, "KLD_options");
    pf_.m_options.loadFromConfigFile(ini, "PF_options");

    odoModel_.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
    odoModel_.gaussianModel.minStdXY =
        ini.read_double("DummyOdometryParams", "minStdXY", odoModel_.gaussianModel.minStdXY);
    odoModel_.gaussianModel.minStdPHI = mrpt::DEG2RAD(ini.read_double(
        "DummyOdometryParams", "minStdPHI", mrpt::RAD2DEG(odoModel_.gaussianModel.minStdPHI)));
}

void LiveLocalizer::addOdometry(const mrpt::obs::CObservationOdometry& odo)
{
    lastOdo_ = odo.odometry;
    if (!odoAtLastStep_) odoAtLastStep_ = odo.odometry;
}

void LiveLocalizer::addBearing(const CObservationWiFiBearing::Ptr& b)
{
    if (!b) return;
    if (!wifiMap_->transmitters().find(b->transmitter))
    {
        ++unknown_;
        return;
    }
    pending_.push_back(b);
}

bool LiveLocalizer::step()
{
    if (pending_.empty()) return false;
    std::stable_sort(
        pending_.begin(), pending_.end(),
        [](const auto& a, const auto& b) { return a->timestamp < b->timestamp; });
    const size_t n = opts_.maxBearingsPerStep == 0
                         ? pending_.size()
                         : std::min(pending_.size(), opts_.maxBearingsPerStep);
    mrpt::obs::CSensoryFrame sf;
    for (size_t i = 0; i < n; ++i) sf.insert(pending_[i]);
    const double t = mrpt::Clock::toDouble(pending_[n - 1]->timestamp);
    pending_.erase(pending_.begin(), pending_.begin() + long(n));

    mrpt::obs::CActionCollection acts;
    if (lastOdo_ && odoAtLastStep_)
    {
        // n offline steps would each have added the noise floor: sqrt(n) times it once.
        auto model = odoModel_;
        model.gaussianModel.minStdXY *= std::sqrt(double(n));
        model.gaussianModel.minStdPHI *= std::sqrt(double(n));
        mrpt::obs::CActionRobotMovement2D act;
        act.computeFromOdometry(*lastOdo_ - *odoAtLastStep_, model);
        acts.insert(act);
        odoAtLastStep_ = lastOdo_;
    }
    else
        acts.insert(unknownMotionAction(
            steps_ ? t - lastStepTime_ : 0.0, opts_.unknownMotionSpeed_mps,
            opts_.unknownMotionTurn_rps));
    pf_.executeOn(pdf_, &acts, &sf);
    lastStepTime_ = t;
    ++steps_;
    bearingsUsed_ += n;
    return true;
}

mrpt::math::TPose2D LiveLocalizer::mean() const
{
    return pdf_.getMeanVal().asTPose();
}

double LiveLocalizer::spread_m() const
{
    const auto [cov, m] = pdf_.getCovarianceAndMean();
    return std::sqrt(std::max(cov(0, 0), cov(1, 1)));
}

LiveDeviceMapper::LiveDeviceMapper(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
    enabled_ = c.read_bool(s, "map_devices", false);
    // wifi-iot-map's command-line defaults
    opts_.model.minStd_rad = mrpt::DEG2RAD(c.read_double(s, "map_min_std_deg", 3.0));
    opts_.model.outlierProb = c.read_double(s, "map_outlier_prob", 0.1);
    opts_.loss = c.read_string(s, "map_loss", "cauchy");
    opts_.gridStep_m = c.read_double(s, "map_grid_m", 0.1);
    updatePeriod_s_ = c.read_double(s, "map_update_period_s", updatePeriod_s_);
    // wifi-iot-map --trust-odometry --odometry-drift "XY YAW"'s defaults
    drift_.sigmaXY_perSqrtM = c.read_double(s, "map_odometry_drift_xy", 0.01);
    drift_.sigmaYaw_perSqrtM = mrpt::DEG2RAD(c.read_double(s, "map_odometry_drift_yaw_deg", 0.3));
    if (!(drift_.sigmaXY_perSqrtM >= 0) || !(drift_.sigmaYaw_perSqrtM >= 0))
        throw std::invalid_argument(
            "[" + s + "] map_odometry_drift_xy and map_odometry_drift_yaw_deg must be >= 0");
    if (!(opts_.model.minStd_rad > 0) || !(opts_.model.outlierProb >= 0) ||
        !(opts_.model.outlierProb < 1) || !(opts_.gridStep_m > 0) || !(updatePeriod_s_ > 0))
        throw std::invalid_argument(
            "[" + s +
            "] map_min_std_deg, map_grid_m and map_update_period_s must be > 0, "
            "map_outlier_prob in [0, 1)");
    if (opts_.loss != "cauchy" && opts_.loss != "huber" && opts_.loss != "none")
        throw std::invalid_argument(
            "[" + s + "] map_loss = " + opts_.loss + ": expected cauchy, huber or none");
}

void LiveDeviceMapper::addOdometry(const mrpt::obs::CObservationOdometry& odo)
{
    odometry_.emplace_back(mrpt::Clock::toDouble(odo.timestamp), odo.odometry.asTPose());
}

void LiveDeviceMapper::addBearing(const CObservationWiFiBearing& b)
{
    auto r = recordFromObservation(b);
    if (r.hasAoa) bearings_.push_back(std::move(r));
}

void LiveDeviceMapper::update()
{
    // The inputs as readRawlog() makes them from a rawlog of the same observations.
    auto odo = odometry_;
    std::stable_sort(
        odo.begin(), odo.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    Trajectory2D traj;
    for (const auto& [t, p] : odo)
        if (traj.empty() || t > traj.t.back()) traj.push_back(t, p);
    auto bearings = bearings_;
    std::stable_sort(
        bearings.begin(), bearings.end(),
        [](const BearingRecord& a, const BearingRecord& b) { return a.t < b.t; });

    warnings_ = InputWarnings();
    devices_.clear();
    if (traj.empty()) return;
    auto allRays = raysFromBearings(bearings, traj, &warnings_);
    // The map trusts the odometry: its drift is in the devices' σ.
    addOdometryDrift(allRays, traj, drift_);
    for (const auto& [mac, rays] : allRays)
    {
        auto d = triangulateDevice(rays, opts_);
        d.mac = mac;
        devices_.push_back(d);
    }
}

}  // namespace mrpt_wifi::localization
