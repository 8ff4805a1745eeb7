/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/localization/BearingLikelihood.h>

namespace mrpt_wifi::localization
{
double recordLogLikelihood(
    const BearingRecord& r, const mrpt::math::TPose2D& robot, const KnownTransmitter& tx,
    const RobustBearingModel& model, const BearingUse& use)
{
    const auto s = sensorWorldPose(robot, r.sensorPose);
    double ll = 0;
    if (use.aoa && r.hasAoa && r.aoaStd <= model.maxStd_rad)
        ll += model.logLikelihood(
            predictAoa(s, tx.pose.x, tx.pose.y), r.aoa, r.aoaAmbiguous, r.aoaMirror,
            model.sigma(r.aoaStd));
    if (use.aod && r.hasAod && r.aodStd <= model.maxStd_rad)
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
    if (use.aoa && r.hasAoa && r.aoaStd <= model.maxStd_rad)
        agrees = within(
            predictAoa(s, tx.pose.x, tx.pose.y), r.aoa, r.aoaAmbiguous, r.aoaMirror, r.aoaStd);
    if (use.aod && r.hasAod && r.aodStd <= model.maxStd_rad)
        agrees =
            agrees.value_or(true) &&
            within(predictAod(tx.pose, s.x, s.y), r.aod, r.aodAmbiguous, r.aodMirror, r.aodStd);
    return agrees;
}

}  // namespace mrpt_wifi::localization
