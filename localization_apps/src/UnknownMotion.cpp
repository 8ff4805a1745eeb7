/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPosePDFParticles.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/localization/UnknownMotion.h>

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

mrpt::obs::CActionRobotMovement2D::Ptr UnknownMotion::makeAction(
    double dt_s, const mrpt::poses::CPose2D& increment) const
{
    // The increment as odometry through MRPT's Gaussian model with all growth terms off: the
    // σ floors become exactly the random walk's σ for this step.
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions mm;
    mm.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
    mm.gaussianModel.a1 = mm.gaussianModel.a2 = 0;
    mm.gaussianModel.a3 = mm.gaussianModel.a4 = 0;
    mm.gaussianModel.minStdXY = float(stdXY(dt_s));
    mm.gaussianModel.minStdPHI = float(stdPhi(dt_s));
    auto a = mrpt::obs::CActionRobotMovement2D::Create();
    a->computeFromOdometry(increment, mm);
    if (wideFraction > 0)
    {
        // The mixture as samples: MRPT's filter draws each particle's step from them.
        UnknownMotion wide = *this;
        wide.correlationTime_s = wideCorrelationTime_s;
        const size_t nSamples = 1000;
        auto pdf = mrpt::poses::CPosePDFParticles::Create(nSamples);
        auto& rng = mrpt::random::getRandomGenerator();
        for (size_t i = 0; i < nSamples; ++i)
        {
            const bool isWide = double(i) < wideFraction * double(nSamples);
            const double sxy = isWide ? wide.stdXY(dt_s) : stdXY(dt_s);
            const double sphi = isWide ? wide.stdPhi(dt_s) : stdPhi(dt_s);
            auto& d = pdf->m_particles[i].d;
            d.x = increment.x() + sxy * rng.drawGaussian1D_normalized();
            d.y = increment.y() + sxy * rng.drawGaussian1D_normalized();
            d.phi = mrpt::math::wrapToPi(increment.phi() + sphi * rng.drawGaussian1D_normalized());
            pdf->m_particles[i].log_w = -std::log(double(nSamples));  // drawn by linear weight
        }
        a->poseChange = pdf;
    }
    return a;
}

void UnknownMotion::loadFromConfigFile(
    const mrpt::config::CConfigFileBase& cfg, const std::string& s)
{
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
    validate();
}

void UnknownMotion::validate() const
{
    auto check = [](double v, const char* what)
    {
        if (!(v > 0) || !std::isfinite(v))
            throw std::invalid_argument(
                std::string("unknown-motion model: ") + what + " must be > 0 (got " +
                std::to_string(v) + ")");
    };
    check(maxSpeed_mps, "max_speed_mps");
    check(maxTurnRate_dps, "max_turn_rate_dps");
    check(correlationTime_s, "correlation_time_s");
    check(maxStep_s, "max_step_s");
    check(minStdXY_m, "min_std_xy");
    check(minStdPhi_deg, "min_std_phi_deg");
    check(velocityWindow_s, "velocity_window_s");
    check(wideCorrelationTime_s, "wide_correlation_time_s");
    if (!(wideFraction >= 0 && wideFraction <= 1))
        throw std::invalid_argument(
            "unknown-motion model: wide_fraction must be in [0, 1] (got " +
            std::to_string(wideFraction) + ")");
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
