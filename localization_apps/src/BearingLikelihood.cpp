/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt/core/format.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>

namespace mrpt_wifi::localization
{
std::string weighedAnglesString(const RobustBearingModel& model, const BearingUse& use)
{
    return mrpt::format(
        "use_aoa = %s, use_aod = %s, max_std_deg = %.1f", use.aoa ? "true" : "false",
        use.aod ? "true" : "false", mrpt::RAD2DEG(model.maxStd_rad));
}

std::vector<AoaDirection> aoaDirections(const BearingRecord& r, double share)
{
    std::vector<AoaDirection> out{{r.aoa, r.aoaMirror, 1.0}};
    if (!(share > 0) || !r.hasAoaAlternative) return out;
    double sum = 0;
    for (const auto& a : r.aoaAlternatives())
    {
        const double w = std::clamp(share * a.weight, 0.0, 1.0);
        out.push_back({a.aoa, aoaMirrorOf(r, a.aoa), w});
        sum += w;
    }
    const double scale = sum > kMaxAlternativesWeight ? kMaxAlternativesWeight / sum : 1.0;
    for (size_t i = 1; i < out.size(); ++i) out[i].weight *= scale;
    out[0].weight = 1 - std::min(sum, kMaxAlternativesWeight);
    return out;
}

double recordLogLikelihood(
    const BearingRecord& r, const mrpt::math::TPose2D& robot, const KnownTransmitter& tx,
    const RobustBearingModel& model, const BearingUse& use)
{
    const auto s = sensorWorldPose(robot, r.sensorPose);
    double ll = 0;
    if (usesAoa(r, model, use) && usesAoaAlternative(r, model))
    {
        // Each direction with its mirror, as logLikelihood() weighs one, by its weight.
        const double sigma = model.sigma(r.aoaDirectionStd);
        const double predicted = predictAoa(s, tx.pose.x, tx.pose.y);
        double density = 0;
        for (const auto& d : aoaDirections(r, model.aoaAlternativeShare))
            density +=
                d.weight * model.inlierDensity(predicted, d.aoa, r.aoaAmbiguous, d.mirror, sigma);
        ll += model.logOfInlierDensity(density);
    }
    else if (usesAoa(r, model, use))
        ll += model.logLikelihood(
            predictAoa(s, tx.pose.x, tx.pose.y), r.aoa, r.aoaAmbiguous, r.aoaMirror,
            model.sigma(r.aoaStd));
    if (usesAod(r, model, use))
        ll += model.logLikelihood(
            predictAod(tx.pose, s.x, s.y), r.aod, r.aodAmbiguous, r.aodMirror,
            model.sigma(r.aodStd));
    return ll;
}

std::optional<bool> recordAgrees(
    const BearingRecord& r, const mrpt::math::TPose2D& robot, const KnownTransmitter& tx,
    const RobustBearingModel& model, const BearingUse& use, double nSigma)
{
    const auto s = sensorWorldPose(robot, r.sensorPose);
    const auto within =
        [&](double predicted, double measured, bool ambiguous, double mirror, double reportedStd)
    {
        const double bound = nSigma * model.sigma(reportedStd);
        return std::abs(wrapToPi(predicted - measured)) <= bound ||
               (ambiguous && std::abs(wrapToPi(predicted - mirror)) <= bound);
    };
    std::optional<bool> agrees;
    if (usesAoa(r, model, use))
    {
        const double predicted = predictAoa(s, tx.pose.x, tx.pose.y);
        const double sd = aoaStdUsed(r, model);
        agrees = false;
        for (const auto& d :
             aoaDirections(r, usesAoaAlternative(r, model) ? model.aoaAlternativeShare : 0.0))
            agrees = *agrees || within(predicted, d.aoa, r.aoaAmbiguous, d.mirror, sd);
    }
    if (usesAod(r, model, use))
        agrees =
            agrees.value_or(true) &&
            within(predictAod(tx.pose, s.x, s.y), r.aod, r.aodAmbiguous, r.aodMirror, r.aodStd);
    return agrees;
}

mrpt::math::CMatrixDouble33 bearingBiasCovariance(
    const mrpt::math::TPose2D& robot, const mrpt::math::TPose2D& sensorOnRobot,
    const std::vector<mrpt::math::TPoint2D>& transmitters, const BearingUse& use,
    double biasStd_rad, double priorStd_m)
{
    Eigen::Matrix3d info =
        Eigen::Vector3d(
            1 / (priorStd_m * priorStd_m), 1 / (priorStd_m * priorStd_m), 1 / (M_PI * M_PI))
            .asDiagonal();
    const auto s = sensorWorldPose(robot, sensorOnRobot);
    const double c = std::cos(robot.phi), sn = std::sin(robot.phi);
    // How the array's position moves with the robot's heading (it sits off the centre).
    const double dsx = -sn * sensorOnRobot.x - c * sensorOnRobot.y;
    const double dsy = c * sensorOnRobot.x - sn * sensorOnRobot.y;
    const double w = 1 / (biasStd_rad * biasStd_rad);
    for (const auto& tx : transmitters)
    {
        const double dx = tx.x - s.x, dy = tx.y - s.y, r2 = dx * dx + dy * dy;
        if (r2 < 1e-4) continue;  // at the transmitter: no direction
        // The direction of the line array–transmitter by the robot's x, y, φ: both angles
        // turn with it; the AoA, in the array's frame, also with the heading itself.
        const Eigen::Vector3d line(dy / r2, -dx / r2, (dy * dsx - dx * dsy) / r2);
        if (use.aod) info += w * line * line.transpose();
        if (use.aoa)
        {
            const Eigen::Vector3d aoa = line - Eigen::Vector3d(0, 0, 1);
            info += w * aoa * aoa.transpose();
        }
    }
    mrpt::math::CMatrixDouble33 cov;
    cov.asEigen() = info.inverse();
    return cov;
}

size_t SharpCoverage::seconds() const
{
    return std::accumulate(secondsWith.begin(), secondsWith.end(), size_t(0));
}

double SharpCoverage::shareWithAtLeast(size_t transmitters) const
{
    const size_t from = std::clamp<size_t>(transmitters, 0, secondsWith.size() - 1);
    const size_t n = std::accumulate(secondsWith.begin() + from, secondsWith.end(), size_t(0));
    return seconds() ? double(n) / double(seconds()) : std::nan("");
}

std::string SharpCoverage::asString() const
{
    const auto percent = [&](size_t k)
    { return mrpt::format("%.0f %%", 100.0 * double(secondsWith[k]) / double(seconds())); };
    if (!seconds()) return "no bearings";
    return "3+ transmitters with a sharp bearing in " + percent(3) + " of " +
           std::to_string(seconds()) + " s (2: " + percent(2) + ", 1: " + percent(1) +
           ", 0: " + percent(0) + ")";
}

SharpCoverage sharpCoverage(
    const std::vector<BearingRecord>& records, const BearingUse& use, double sharpStd_rad)
{
    SharpCoverage c;
    if (records.empty()) return c;
    const auto [first, last] = std::minmax_element(
        records.begin(), records.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
    const double t0 = first->t;
    if (!std::isfinite(last->t - t0)) return c;
    std::vector<std::set<MacAddress>> sharpIn(size_t(std::floor(last->t - t0)) + 1);
    for (const auto& r : records)
    {
        const bool sharp = (use.aoa && r.hasAoa && r.aoaStd <= sharpStd_rad) ||
                           (use.aod && r.hasAod && r.aodStd <= sharpStd_rad);
        if (sharp) sharpIn[size_t(std::floor(r.t - t0))].insert(r.transmitter);
    }
    for (const auto& s : sharpIn) ++c.secondsWith[std::min(s.size(), c.secondsWith.size() - 1)];
    return c;
}

}  // namespace mrpt_wifi::localization
