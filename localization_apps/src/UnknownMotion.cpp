/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt/poses/CPose2D.h>
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

mrpt::obs::CActionRobotMovement2D::Ptr UnknownMotion::makeAction(double dt_s) const
{
    // A zero odometry increment through MRPT's Gaussian model with all growth terms off: the
    // σ floors become exactly the random walk's σ for this step.
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions mm;
    mm.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
    mm.gaussianModel.a1 = mm.gaussianModel.a2 = 0;
    mm.gaussianModel.a3 = mm.gaussianModel.a4 = 0;
    mm.gaussianModel.minStdXY = float(stdXY(dt_s));
    mm.gaussianModel.minStdPHI = float(stdPhi(dt_s));
    auto a = mrpt::obs::CActionRobotMovement2D::Create();
    a->computeFromOdometry(mrpt::poses::CPose2D(0, 0, 0), mm);
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
}

std::string UnknownMotion::asString() const
{
    std::ostringstream o;
    o << "random walk, max speed " << maxSpeed_mps << " m/s, max turn rate " << maxTurnRate_dps
      << " deg/s, tau " << correlationTime_s << " s";
    return o.str();
}

}  // namespace mrpt_wifi::localization
