/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/Clock.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/IniValues.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/obs/ConfigKeys.h>
#include <mrpt_wifi/obs/ConfigPaths.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace mrpt_wifi::localization
{
CWiFiBearingMap::Ptr wifiMapFromIni(
    const mrpt::config::CConfigFileBase& ini, const std::string& iniDir)
{
    mrpt::maps::TSetOfMetricMapInitializers inits;
    inits.loadFromConfigFile(ini, "MetricMap");
    for (auto& i : inits)
        if (auto* w = dynamic_cast<CWiFiBearingMap::TMapDefinition*>(i.get()))
        {
            // From the .ini's folder, else the working directory, else the data folder.
            auto& f = w->transmittersFile;
            const auto r = config::resolveConfigPath(
                f, iniDir, "localization",
                "[MetricMap_wifiBearingMap_00_creationOpts] transmitters_file");
            if (!r.note.empty()) std::fprintf(stderr, "note: %s\n", r.note.c_str());
            f = r.path;
        }
    mrpt::maps::CMultiMetricMap maps;
    maps.setListOfMaps(inits);
    auto wifiMap = maps.mapByClass<CWiFiBearingMap>();
    if (!wifiMap)
        throw std::runtime_error(
            "the [MetricMap] section creates no wifiBearingMap (wifiBearingMap_count=1 missing?)");
    if (wifiMap->transmitters().empty())
        throw std::runtime_error(
            "the WiFi map has no transmitters: set transmitters_file in "
            "[MetricMap_wifiBearingMap_00_creationOpts]");
    return wifiMap;
}

std::optional<mrpt::math::TBoundingBox> initialPdfArea(const mrpt::config::CConfigFileBase& ini)
{
    const std::string sect = "LocalizationExperiment";
    requireIniNumbers(ini, sect, {"init_PDF_mode"});
    if (ini.read_int(sect, "init_PDF_mode", 1) != 1) return std::nullopt;
    requireIniNumbers(
        ini, sect,
        {"init_PDF_min_x", "init_PDF_max_x", "init_PDF_min_y", "init_PDF_max_y",
         "init_PDF_min_yaw_deg", "init_PDF_max_yaw_deg"});
    for (const char* k : {"init_PDF_min_x", "init_PDF_max_x", "init_PDF_min_y", "init_PDF_max_y"})
        if (!ini.keyExists(sect, k)) return std::nullopt;
    const auto rd = [&](const char* k) { return ini.read_double(sect, k, 0); };
    const mrpt::math::TBoundingBox box(
        {rd("init_PDF_min_x"), rd("init_PDF_min_y"), 0},
        {rd("init_PDF_max_x"), rd("init_PDF_max_y"), 0},
        mrpt::math::TBoundingBox::CTOR_FLAGS::AllowUnordered);
    if (!(box.max.x > box.min.x) || !(box.max.y > box.min.y)) return std::nullopt;
    return box;
}

std::string boxText(const mrpt::math::TBoundingBox& b)
{
    char buf[160];
    std::snprintf(buf, sizeof(buf), "x %g..%g, y %g..%g m", b.min.x, b.max.x, b.min.y, b.max.y);
    return buf;
}

bool boundByInitialPdf(
    CWiFiBearingMap& map, const mrpt::config::CConfigFileBase& ini, std::string* warning)
{
    if (warning) warning->clear();
    if (map.areaFromInitialPdf()) return true;  // the map definition took it already
    const auto box = initialPdfArea(ini);
    if (!map.area())
    {
        if (box) map.setArea(box);
        return box.has_value();
    }
    if (!box) return false;
    // Both given: one of them is most likely a leftover of another building (a copied .ini
    // with only one of the two edited).
    const auto area = *map.area();
    constexpr double tol = 1e-6;
    const bool boxInside = box->min.x >= area.min.x - tol && box->max.x <= area.max.x + tol &&
                           box->min.y >= area.min.y - tol && box->max.y <= area.max.y + tol;
    const std::string areaKeys =
        "the map's area ([MetricMap_wifiBearingMap_00_creationOpts] min_x, max_x, min_y, "
        "max_y: ";
    const std::string boxKeys =
        "the init_PDF box ([LocalizationExperiment] init_PDF_min_x, init_PDF_max_x, "
        "init_PDF_min_y, init_PDF_max_y: ";
    const std::string howToFix =
        "Leave min_x ... max_y out of the map's creationOpts to take the area from the "
        "init_PDF box, or make the two agree.";
    if (!boxInside)
    {
        // A robot the user says may be anywhere in the box must not die at the area's edge:
        // the area grows to cover the box.
        mrpt::math::TBoundingBox both = area;
        both.min.x = std::min(area.min.x, box->min.x);
        both.max.x = std::max(area.max.x, box->max.x);
        both.min.y = std::min(area.min.y, box->min.y);
        both.max.y = std::max(area.max.y, box->max.y);
        map.setArea(both);
        if (warning)
            *warning = boxKeys + boxText(*box) + ") reaches outside " + areaKeys + boxText(area) +
                       "): the area is widened to " + boxText(both) + " to cover both. " + howToFix;
        return false;
    }
    const bool same =
        std::abs(box->min.x - area.min.x) <= tol && std::abs(box->max.x - area.max.x) <= tol &&
        std::abs(box->min.y - area.min.y) <= tol && std::abs(box->max.y - area.max.y) <= tol;
    if (!same && warning)
        *warning = areaKeys + boxText(area) + ") is larger than " + boxKeys + boxText(*box) +
                   "): the filter starts inside the box only and finds a robot elsewhere in the "
                   "area only by [ParticleRecovery] re-seeding. For a kidnapped robot give the "
                   "box the whole area. " +
                   howToFix;
    return false;
}

mrpt::obs::CActionRobotMovement2D::TMotionModelOptions odometryMotionModel(
    const mrpt::config::CConfigFileBase& ini)
{
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions m;
    m.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
    m.gaussianModel.minStdXY =
        ini.read_double("DummyOdometryParams", "minStdXY", m.gaussianModel.minStdXY);
    m.gaussianModel.minStdPHI = mrpt::DEG2RAD(ini.read_double(
        "DummyOdometryParams", "minStdPHI", mrpt::RAD2DEG(m.gaussianModel.minStdPHI)));
    return m;
}

void LiveLocalizerOptions::loadFromConfigFile(
    const mrpt::config::CConfigFileBase& c, const std::string& s)
{
    // Also names the former keys: the live filter's own random walk is gone (both filters
    // read [UnknownMotion]), bearing_tx_array is the sensor's bearing_tx_arrays.
    config::requireKnownKeys(c, s, config::sectionKeys("wifi-localize"));
    requireIniNumbers(c, s, {"max_bearings_per_step", "max_queue_s", "bearing_bias_std_deg"});
    const int maxPerStep = c.read_int(s, "max_bearings_per_step", int(maxBearingsPerStep));
    if (maxPerStep < 0)
        throw std::invalid_argument("[" + s + "] max_bearings_per_step must be >= 0");
    maxBearingsPerStep = size_t(maxPerStep);
    maxQueue_s = c.read_double(s, "max_queue_s", maxQueue_s);
    if (!(maxQueue_s >= 0) || !std::isfinite(maxQueue_s))
        throw std::invalid_argument("[" + s + "] max_queue_s must be >= 0");
    bearingBiasStd_deg = c.read_double(s, "bearing_bias_std_deg", bearingBiasStd_deg);
    if (!(bearingBiasStd_deg >= 0) || !std::isfinite(bearingBiasStd_deg))
        throw std::invalid_argument("[" + s + "] bearing_bias_std_deg must be >= 0");
}

LiveLocalizer::LiveLocalizer(const mrpt::config::CConfigFileBase& ini, const std::string& iniDir)
{
    opts_.loadFromConfigFile(ini, "wifi-localize");

    // The map, as wifi-pf-localization builds it (relative transmitters_file: cwd, then iniDir),
    // bounded by the init_PDF box unless it sets its own area.
    wifiMap_ = wifiMapFromIni(ini, iniDir);
    areaFromInitPdf_ = boundByInitialPdf(*wifiMap_, ini, &areaWarning_);
    map_->maps.push_back(wifiMap_);
    motion_.loadFromConfigFile(ini, "UnknownMotion");
    cv_ = ConstantVelocityPrediction(motion_);
    // Until odometry arrives the motion is unknown: its tempering of the bearings applies.
    mapBearingWeight_ = wifiMap_->likelihoodOptions.bearingWeight;
    wifiMap_->likelihoodOptions.bearingWeight =
        mapBearingWeight_ * motionBearingWeight(false, motion_, odoMotion_);
    recoveryOptions_.loadFromConfigFile(ini, "ParticleRecovery");
    recovery_.emplace(recoveryOptions_, wifiMap_.get());
    WindowSmootherOptions smootherOptions;
    smootherOptions.loadFromConfigFile(ini, "WindowSmoother");
    smootherOptions.graph.useAoa = wifiMap_->likelihoodOptions.use.aoa;
    smootherOptions.graph.useAod = wifiMap_->likelihoodOptions.use.aod;
    smootherOptions.graph.useAoaAlternatives =
        wifiMap_->likelihoodOptions.model.aoaAlternativeShare > 0;
    smootherOptions.track.forwardOnly = motion_.forwardOnly;  // without odometry
    smoother_ = WindowSmoother(smootherOptions, wifiMap_->transmitters());
    smoother_.setArea(wifiMap_->area());

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

    odoModel_ = odometryMotionModel(ini);
    if (ini.sectionExists("OdometryMotion"))
    {
        odoMotion_.emplace();
        odoMotion_->loadFromConfigFile(ini, "OdometryMotion");
    }
}

void LiveLocalizer::addOdometry(const mrpt::obs::CObservationOdometry& odo)
{
    // From the first reading on, odometry drives the filter: its bearing weight applies.
    if (!lastOdo_)
        wifiMap_->likelihoodOptions.bearingWeight =
            mapBearingWeight_ * motionBearingWeight(true, motion_, odoMotion_);
    lastOdo_ = odo.odometry;
    if (!odoAtLastStep_) odoAtLastStep_ = odo.odometry;
    smoother_.addOdometry(mrpt::Clock::toDouble(odo.timestamp), odo.odometry.asTPose());
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

bool LiveLocalizer::step(std::optional<double> now_s)
{
    if (pending_.empty()) return false;
    std::stable_sort(
        pending_.begin(), pending_.end(),
        [](const auto& a, const auto& b) { return a->timestamp < b->timestamp; });
    size_t n = pending_.size();
    if (opts_.maxBearingsPerStep > 0)
    {
        const double newest = mrpt::Clock::toDouble(pending_.back()->timestamp);
        const double overdueBefore = std::max(newest, now_s.value_or(newest)) - opts_.maxQueue_s;
        const auto firstInTime = std::find_if(
            pending_.begin(), pending_.end(),
            [&](const auto& b) { return mrpt::Clock::toDouble(b->timestamp) >= overdueBefore; });
        n = std::min(n, std::max(opts_.maxBearingsPerStep, size_t(firstInTime - pending_.begin())));
    }
    mrpt::obs::CSensoryFrame sf;
    for (size_t i = 0; i < n; ++i) sf.insert(pending_[i]);
    const double t = mrpt::Clock::toDouble(pending_[n - 1]->timestamp);
    pending_.erase(pending_.begin(), pending_.begin() + long(n));

    const double dt = steps_ ? t - lastStepTime_ : 0.0;
    mrpt::obs::CActionRobotMovement2D act;
    if (lastOdo_ && odoAtLastStep_)
    {
        const mrpt::poses::CPose2D increment = *lastOdo_ - *odoAtLastStep_;
        if (odoMotion_)  // its spread depends on time and distance, not on the step count
            act = *odoMotion_->makeAction(dt, increment);
        else
        {
            // n offline steps would each have added the noise floor: sqrt(n) times it once.
            auto model = odoModel_;
            model.gaussianModel.minStdXY *= std::sqrt(double(n));
            model.gaussianModel.minStdPHI *= std::sqrt(double(n));
            act.computeFromOdometry(increment, model);
        }
        odoAtLastStep_ = lastOdo_;
    }
    else
        act = *motion_.makeAction(dt, cv_.predictIncrement(t));
    for (const auto& o : sf)
    {
        const auto& b = static_cast<const CObservationWiFiBearing&>(*o);
        recovery_->checkBearing(mrpt::Clock::toDouble(o->timestamp), b);
        // Heard: a bearing with an angle the map's likelihood uses; a wide or missing one
        // constrains nothing.
        const auto record = recordFromObservation(b);
        const auto& lo = wifiMap_->likelihoodOptions;
        if (recordWeighed(record, lo.model, lo.use))
        {
            auto& heard = heard_[b.transmitter];
            heard = std::max(heard, mrpt::Clock::toDouble(o->timestamp));
            ++bearingsWeighed_;
        }
        sensorOnRobot_ = mrpt::poses::CPose2D(b.sensorPose).asTPose();
        if (smoother_.options().enabled) smoother_.addBearing(record);
    }
    if (const double f = recovery_->reseedFraction(t, dt); f > 0)
        act = withReseeding(act, f, recovery_->reseedRadius_m());
    mrpt::obs::CActionCollection acts;
    acts.insert(act);
    pf_.executeOn(pdf_, &acts, &sf);
    const auto estimate = mean();
    if (!lastOdo_) cv_.addEstimate(t, estimate);
    recovery_->setEstimate(estimate);
    smoothed_.reset();
    smoothed_ = smoother_.update(t, estimate, [this] { return spread_m(); });
    if (smoothed_)
        lastSmootherOffset_.emplace(
            smoothed_->x - estimate.x, smoothed_->y - estimate.y,
            mrpt::math::wrapToPi(smoothed_->phi - estimate.phi));
    lastStepTime_ = t;
    ++steps_;
    bearingsUsed_ += n;
    return true;
}

mrpt::math::TPose2D LiveLocalizer::mean() const
{
    return pdf_.getMeanVal().asTPose();
}

LiveLocalizer::Uncertainty LiveLocalizer::uncertainty() const
{
    const auto [particles, mean] = pdf_.getCovarianceAndMean();
    Uncertainty u{particles, particles, mean.asTPose()};
    // The reported pose is the smoother's, not the particles' mean: the particles' squared
    // error about it is their covariance plus the offset's outer product.
    const auto reportedPose = estimateGiven(u.particlesMean);
    const Eigen::Vector3d offset(
        reportedPose.x - u.particlesMean.x, reportedPose.y - u.particlesMean.y,
        mrpt::math::wrapToPi(reportedPose.phi - u.particlesMean.phi));
    u.reported.asEigen() += offset * offset.transpose();
    // Without the smoother's estimate the mean is reported, off by what it was last seen off.
    if (!smoothed_ && lastSmootherOffset_)
    {
        const auto& d = *lastSmootherOffset_;
        const double distance2 = d.x * d.x + d.y * d.y;
        u.reported(0, 0) += distance2;
        u.reported(1, 1) += distance2;
        u.reported(2, 2) += d.phi * d.phi;
    }
    if (!(opts_.bearingBiasStd_deg > 0)) return u;
    // A transmitter heard in the last few seconds constrains the pose now.
    const double kHeardWithin_s = 5.0;
    std::vector<mrpt::math::TPoint2D> txs;
    for (const auto& [mac, t] : heard_)
        if (t >= lastStepTime_ - kHeardWithin_s)
            if (const auto* tx = wifiMap_->transmitters().find(mac))
                txs.emplace_back(tx->pose.x, tx->pose.y);
    const auto& a = wifiMap_->area();
    const double prior_m = a ? std::hypot(a->max.x - a->min.x, a->max.y - a->min.y) : 100.0;
    u.reported += bearingBiasCovariance(
        reportedPose, sensorOnRobot_, txs, wifiMap_->likelihoodOptions.use,
        mrpt::DEG2RAD(opts_.bearingBiasStd_deg), prior_m);
    return u;
}

double LiveLocalizer::spread_m() const
{
    const auto [cov, m] = pdf_.getCovarianceAndMean();
    return std::sqrt(std::max(cov(0, 0), cov(1, 1)));
}

void LagRecord::add(double lag_s)
{
    ++counts_[std::llround(lag_s / kResolution_s)];
    ++count_;
}

double LagRecord::percentile(double q) const
{
    if (count_ == 0) return NAN;
    const uint64_t rank =
        std::min(count_ - 1, uint64_t(std::max(0.0, q) * double(count_)));  // 0-based
    uint64_t below = 0;
    for (const auto& [bin, n] : counts_)
    {
        below += n;
        if (below > rank) return double(bin) * kResolution_s;
    }
    return double(counts_.rbegin()->first) * kResolution_s;
}

LiveDeviceMapper::LiveDeviceMapper(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
    requireIniBools(c, s, {"map_devices"});
    requireIniNumbers(
        c, s,
        {"map_min_std_deg", "map_outlier_prob", "map_grid_m", "map_update_period_s",
         "map_odometry_drift_xy", "map_odometry_drift_yaw_deg"});
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
