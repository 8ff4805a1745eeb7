/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPosePDFParticles.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/localization/IniValues.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/obs/ConfigKeys.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::localization
{
double UnknownMotion::stdXY(double dt_s) const
{
    const double dt = std::clamp(dt_s, 0.0, maxStep_s);
    return std::max(minStdXY_m, maxSpeed_mps * std::sqrt(dt * correlationTime_s));
}

double UnknownMotion::stdPhi(double dt_s) const
{
    const double dt = std::clamp(dt_s, 0.0, maxStep_s);
    return std::max(
        mrpt::DEG2RAD(minStdPhi_deg),
        mrpt::DEG2RAD(maxTurnRate_dps) * std::sqrt(dt * correlationTime_s));
}

namespace
{
/** Gaussian step of mean `increment` (MRPT's model with all growth terms off: its σ floors are
 *  exactly the given σ), or with `wideFraction > 0` the two-Gaussian mixture as weighted
 *  samples, which MRPT's filter draws each particle's step from: 150 for the tight part and 50
 *  for the wide one, weighted by their shares, fresh every step. Equal weights would give the
 *  wide part a handful of distinct steps (2 % of the samples) for all the particles that take
 *  it; and CPosePDFParticles::drawSingleSample walks the samples' cumulative weights, so each
 *  particle's draw costs their number (1000 equal samples made a filter step 4.5x slower). */
mrpt::obs::CActionRobotMovement2D::Ptr walkAction(
    const mrpt::poses::CPose2D& increment, double stdXY, double stdPhi, double wideStdXY,
    double wideStdPhi, double wideFraction)
{
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions mm;
    mm.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
    mm.gaussianModel.a1 = mm.gaussianModel.a2 = 0;
    mm.gaussianModel.a3 = mm.gaussianModel.a4 = 0;
    mm.gaussianModel.minStdXY = float(stdXY);
    mm.gaussianModel.minStdPHI = float(stdPhi);
    auto a = mrpt::obs::CActionRobotMovement2D::Create();
    // Also fills the action's raw odometry increment.
    a->computeFromOdometry(increment, mm);
    if (wideFraction <= 0)
    {
        keepUsableByMrptFilter(*a);
        return a;
    }
    const size_t nWide = 50, nTight = wideFraction < 1 ? 150 : 0;
    auto pdf = mrpt::poses::CPosePDFParticles::Create(nTight + nWide);
    auto& rng = mrpt::random::getRandomGenerator();
    for (size_t i = 0; i < nTight + nWide; ++i)
    {
        const bool isWide = i >= nTight;
        const double sxy = isWide ? wideStdXY : stdXY;
        const double sphi = isWide ? wideStdPhi : stdPhi;
        auto& d = pdf->m_particles[i].d;
        d.x = increment.x() + sxy * rng.drawGaussian1D_normalized();
        d.y = increment.y() + sxy * rng.drawGaussian1D_normalized();
        d.phi = mrpt::math::wrapToPi(increment.phi() + sphi * rng.drawGaussian1D_normalized());
        // drawSingleSample() reads linear weights.
        pdf->m_particles[i].log_w = isWide ? std::log(wideFraction / double(nWide))
                                           : std::log((1 - wideFraction) / double(nTight));
    }
    a->poseChange = pdf;
    keepUsableByMrptFilter(*a);
    return a;
}

void requirePositive(double v, const std::string& what)
{
    if (!(v > 0) || !std::isfinite(v))
        throw std::invalid_argument(what + " must be > 0 (got " + std::to_string(v) + ")");
}
void requireNonNegative(double v, const std::string& what)
{
    if (!(v >= 0) || !std::isfinite(v))
        throw std::invalid_argument(what + " must be >= 0 (got " + std::to_string(v) + ")");
}
void requireFraction(double v, const std::string& what)
{
    if (!(v >= 0 && v <= 1))
        throw std::invalid_argument(what + " must be in [0, 1] (got " + std::to_string(v) + ")");
}
}  // namespace

void keepUsableByMrptFilter(mrpt::obs::CActionRobotMovement2D& action)
{
    // The limit of CActionCollection::getBestMovementEstimation() (MRPT 2.5).
    constexpr double kMrptMaxMovementCovDet = 1e3;
    if (!action.poseChange) return;
    const double det = action.poseChange->getCovariance().det();
    if (!(det < kMrptMaxMovementCovDet))
        action.estimationMethod = mrpt::obs::CActionRobotMovement2D::emScan2DMatching;
}

mrpt::obs::CActionRobotMovement2D::Ptr UnknownMotion::makeAction(
    double dt_s, const mrpt::poses::CPose2D& increment) const
{
    UnknownMotion wide = *this;
    wide.correlationTime_s = wideCorrelationTime_s;
    return walkAction(
        increment, stdXY(dt_s), stdPhi(dt_s), wide.stdXY(dt_s), wide.stdPhi(dt_s), wideFraction);
}

void UnknownMotion::loadFromConfigFile(
    const mrpt::config::CConfigFileBase& cfg, const std::string& s)
{
    config::requireKnownKeys(cfg, s, config::sectionKeys("UnknownMotion"));
    requireIniNumbers(
        cfg, s,
        {"max_speed_mps", "max_turn_rate_dps", "correlation_time_s", "max_step_s", "min_std_xy",
         "min_std_phi_deg", "velocity_window_s", "wide_fraction", "wide_correlation_time_s",
         "bearing_weight"});
    requireIniBools(cfg, s, {"constant_velocity", "forward_only"});
    maxSpeed_mps = cfg.read_double(s, "max_speed_mps", maxSpeed_mps);
    maxTurnRate_dps = cfg.read_double(s, "max_turn_rate_dps", maxTurnRate_dps);
    correlationTime_s = cfg.read_double(s, "correlation_time_s", correlationTime_s);
    maxStep_s = cfg.read_double(s, "max_step_s", maxStep_s);
    minStdXY_m = cfg.read_double(s, "min_std_xy", minStdXY_m);
    minStdPhi_deg = cfg.read_double(s, "min_std_phi_deg", minStdPhi_deg);
    constantVelocity = cfg.read_bool(s, "constant_velocity", constantVelocity);
    velocityWindow_s = cfg.read_double(s, "velocity_window_s", velocityWindow_s);
    forwardOnly = cfg.read_bool(s, "forward_only", forwardOnly);
    wideFraction = cfg.read_double(s, "wide_fraction", wideFraction);
    wideCorrelationTime_s = cfg.read_double(s, "wide_correlation_time_s", wideCorrelationTime_s);
    bearingWeight = cfg.read_double(s, "bearing_weight", bearingWeight);
    validate();
}

void UnknownMotion::validate() const
{
    const std::string m = "unknown-motion model: ";
    requirePositive(maxSpeed_mps, m + "max_speed_mps");
    requirePositive(maxTurnRate_dps, m + "max_turn_rate_dps");
    requirePositive(correlationTime_s, m + "correlation_time_s");
    requirePositive(maxStep_s, m + "max_step_s");
    requirePositive(minStdXY_m, m + "min_std_xy");
    requirePositive(minStdPhi_deg, m + "min_std_phi_deg");
    requirePositive(velocityWindow_s, m + "velocity_window_s");
    requirePositive(wideCorrelationTime_s, m + "wide_correlation_time_s");
    requireFraction(wideFraction, m + "wide_fraction");
    requirePositive(bearingWeight, m + "bearing_weight");
    requireFraction(bearingWeight, m + "bearing_weight");
}

std::string UnknownMotion::asString() const
{
    std::ostringstream o;
    o << (constantVelocity ? "constant velocity + random walk" : "random walk") << ", max speed "
      << maxSpeed_mps << " m/s, max turn rate " << maxTurnRate_dps << " deg/s, tau "
      << correlationTime_s << " s";
    if (constantVelocity)
        o << ", velocity over " << velocityWindow_s << " s"
          << (forwardOnly ? ", forward only" : "");
    if (wideFraction > 0)
        o << ", " << 100 * wideFraction << " % of steps with tau " << wideCorrelationTime_s << " s";
    if (bearingWeight != 1) o << ", bearings weighted " << bearingWeight;
    return o.str();
}

double OdometryMotion::stdXY(double dt_s, double distance_m) const
{
    const double dt = std::clamp(dt_s, 0.0, maxStep_s);
    return std::sqrt(
        stdXY_per_sqrt_m * stdXY_per_sqrt_m * std::abs(distance_m) +
        stdXY_per_sqrt_s * stdXY_per_sqrt_s * dt);
}

double OdometryMotion::stdPhi(double dt_s, double distance_m) const
{
    const double dt = std::clamp(dt_s, 0.0, maxStep_s);
    const double perM = mrpt::DEG2RAD(stdPhi_deg_per_sqrt_m);
    const double perS = mrpt::DEG2RAD(stdPhi_deg_per_sqrt_s);
    return std::sqrt(perM * perM * std::abs(distance_m) + perS * perS * dt);
}

mrpt::obs::CActionRobotMovement2D::Ptr OdometryMotion::makeAction(
    double dt_s, const mrpt::poses::CPose2D& increment) const
{
    const double d = increment.norm();
    // A zero σ would make MRPT's Gaussian singular (a zero step at dt = 0).
    const double sxy = std::max(stdXY(dt_s, d), 1e-6);
    const double sphi = std::max(stdPhi(dt_s, d), 1e-8);
    const double jumpShare = 1.0 - std::exp(-jumpRate_hz * std::clamp(dt_s, 0.0, maxStep_s));
    return walkAction(
        increment, sxy, sphi, std::hypot(sxy, jumpStdXY_m),
        std::hypot(sphi, mrpt::DEG2RAD(jumpStdPhi_deg)), jumpShare);
}

void OdometryMotion::loadFromConfigFile(
    const mrpt::config::CConfigFileBase& cfg, const std::string& s)
{
    requireIniNumbers(
        cfg, s,
        {"std_xy_per_sqrt_m", "std_phi_deg_per_sqrt_m", "std_xy_per_sqrt_s",
         "std_phi_deg_per_sqrt_s", "max_step_s", "jump_rate_hz", "jump_std_xy_m",
         "jump_std_phi_deg", "bearing_weight"});
    config::requireKnownKeys(cfg, s, config::sectionKeys("OdometryMotion"));
    stdXY_per_sqrt_m = cfg.read_double(s, "std_xy_per_sqrt_m", stdXY_per_sqrt_m);
    stdPhi_deg_per_sqrt_m = cfg.read_double(s, "std_phi_deg_per_sqrt_m", stdPhi_deg_per_sqrt_m);
    stdXY_per_sqrt_s = cfg.read_double(s, "std_xy_per_sqrt_s", stdXY_per_sqrt_s);
    stdPhi_deg_per_sqrt_s = cfg.read_double(s, "std_phi_deg_per_sqrt_s", stdPhi_deg_per_sqrt_s);
    maxStep_s = cfg.read_double(s, "max_step_s", maxStep_s);
    jumpRate_hz = cfg.read_double(s, "jump_rate_hz", jumpRate_hz);
    jumpStdXY_m = cfg.read_double(s, "jump_std_xy_m", jumpStdXY_m);
    jumpStdPhi_deg = cfg.read_double(s, "jump_std_phi_deg", jumpStdPhi_deg);
    bearingWeight = cfg.read_double(s, "bearing_weight", bearingWeight);
    validate();
}

void OdometryMotion::validate() const
{
    const std::string m = "odometry motion model: ";
    requirePositive(stdXY_per_sqrt_m, m + "std_xy_per_sqrt_m");
    requirePositive(stdPhi_deg_per_sqrt_m, m + "std_phi_deg_per_sqrt_m");
    requirePositive(stdXY_per_sqrt_s, m + "std_xy_per_sqrt_s");
    requirePositive(stdPhi_deg_per_sqrt_s, m + "std_phi_deg_per_sqrt_s");
    requirePositive(maxStep_s, m + "max_step_s");
    requireNonNegative(jumpRate_hz, m + "jump_rate_hz");
    requireNonNegative(jumpStdXY_m, m + "jump_std_xy_m");
    requireNonNegative(jumpStdPhi_deg, m + "jump_std_phi_deg");
    requirePositive(bearingWeight, m + "bearing_weight");
    requireFraction(bearingWeight, m + "bearing_weight");
}

double motionBearingWeight(
    bool withOdometry, const UnknownMotion& unknown, const std::optional<OdometryMotion>& odometry)
{
    if (!withOdometry) return unknown.bearingWeight;
    return odometry ? odometry->bearingWeight : 1.0;
}

std::string OdometryMotion::asString() const
{
    std::ostringstream o;
    o << "odometry + random walk of " << stdXY_per_sqrt_m << " m/sqrt(m), " << stdPhi_deg_per_sqrt_m
      << " deg/sqrt(m), " << stdXY_per_sqrt_s << " m/sqrt(s), " << stdPhi_deg_per_sqrt_s
      << " deg/sqrt(s)";
    if (jumpRate_hz > 0)
        o << ", jumps of " << jumpStdXY_m << " m, " << jumpStdPhi_deg << " deg at " << jumpRate_hz
          << "/s";
    if (bearingWeight != 1) o << ", bearings weighted " << bearingWeight;
    return o.str();
}

void ConstantVelocityPrediction::addEstimate(double t_s, const mrpt::math::TPose2D& estimate)
{
    // A new run (time going backwards) or a gap the walk restarts after: forget the past.
    if (!hist_.empty() && (t_s < hist_.back().first || t_s - hist_.back().first > m_.maxStep_s))
        hist_.clear();
    hist_.emplace_back(t_s, estimate);
    // Keep one estimate at or before the window's start.
    while (hist_.size() > 2 && t_s - hist_[1].first >= m_.velocityWindow_s) hist_.pop_front();
}

mrpt::poses::CPose2D ConstantVelocityPrediction::predictIncrement(double t_s) const
{
    if (!m_.constantVelocity || hist_.size() < 2) return {};
    const auto& [ta, a] = hist_.front();
    const auto& [tb, b] = hist_.back();
    const double span = tb - ta;
    if (span < 0.5 * m_.velocityWindow_s) return {};
    // Velocity in the world frame from the displacement over the window (a least-squares slope
    // over all its estimates was tried: it lags more in turns and tracked worse), then the motion
    // over dt from the newest estimate, in the newest estimate's frame (the frame each particle
    // applies its action in), bounded by the top speed and turn rate.
    const double vx = (b.x - a.x) / span, vy = (b.y - a.y) / span;
    const double w = mrpt::math::wrapToPi(b.phi - a.phi) / span;
    const double dt = std::clamp(t_s - tb, 0.0, m_.maxStep_s);
    const double c = std::cos(b.phi), s = std::sin(b.phi);
    double dx = (c * vx + s * vy) * dt, dy = m_.forwardOnly ? 0.0 : (-s * vx + c * vy) * dt;
    // A robot that drives along its heading drives forwards: an estimate moving against its own
    // heading is the mirror of the truth (a linear array's front/back ambiguity), not a robot
    // reversing, and predicting it would only hold the filter there.
    if (m_.forwardOnly) dx = std::max(dx, 0.0);
    const double d = std::hypot(dx, dy), dMax = m_.maxSpeed_mps * dt;
    if (d > dMax) dx *= dMax / d, dy *= dMax / d;
    const double wMax = mrpt::DEG2RAD(m_.maxTurnRate_dps);
    return mrpt::poses::CPose2D(dx, dy, std::clamp(w, -wMax, wMax) * dt);
}

}  // namespace mrpt_wifi::localization
