/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/math/wrap2pi.h>
#include <mrpt_wifi/obs/bearing/BearingTracker.h>

#include <algorithm>
#include <cmath>

namespace mrpt_wifi::bearing
{
BearingTracker::Decision BearingTracker::update(
    const MacAddress& tx, double t_s, const std::optional<mrpt::math::TPose2D>& pose,
    const AntennaArray& rx, const std::vector<BearingCandidate>& candidates, double std_rad)
{
    Decision dec;
    if (candidates.empty()) return dec;
    const bool linear = rx.size() >= 2 && rx.isLinear();
    const double broadside = rx.broadside();
    // Linear arrays: the angle from broadside in the front half-plane, [−π/2, π/2], which
    // moves continuously with the robot (it reflects at the endfires, never jumps across).
    const auto toTrack = [&](double theta)
    {
        if (!linear) return wrapAngle(theta);
        double a = wrapAngle(theta - broadside);
        if (a > M_PI / 2) a = M_PI - a;
        if (a < -M_PI / 2) a = -M_PI - a;
        return a;
    };
    const auto difference = [&](double a, double b) { return linear ? a - b : wrapAngle(a - b); };

    Track& tr = tracks_[tx];
    const double dt = t_s - tr.t_s;
    const bool restart = tr.hits == 0 || dt < 0 || dt > opts_.forgetAfter_s ||
                         pose.has_value() != tr.pose.has_value();
    const double sd = std::clamp(std_rad, opts_.minStd_rad, opts_.maxStd_rad);
    const double z0 = toTrack(candidates[0].theta_rad);
    // A window that says itself it can't tell (σ beyond ambiguousStd_rad) is no evidence of
    // where the transmitter is: it never starts a track (one started at the wrong endfire
    // would then swap the right windows away).
    const bool windowIsSure = std_rad <= opts_.ambiguousStd_rad;
    if (restart && !windowIsSure)
    {
        if (tr.hits > 0 && (dt < 0 || dt > opts_.forgetAfter_s)) tr = Track();
        dec.predicted_rad = candidates[0].theta_rad;
        dec.trackStd_rad = sd;
        return dec;
    }
    if (restart)
    {
        tr = Track();
        tr.angle = z0;
        tr.var = sd * sd;
        tr.hits = 1;
        tr.t_s = t_s;
        tr.pose = pose;
        dec.predicted_rad = candidates[0].theta_rad;
        dec.trackStd_rad = sd;
        return dec;
    }
    // Predict.
    double dvar = opts_.processNoise * opts_.processNoise * dt;
    if (pose && tr.pose)
    {
        const double turn = mrpt::math::wrapToPi(pose->phi - tr.pose->phi);
        const double ds = std::hypot(pose->x - tr.pose->x, pose->y - tr.pose->y);
        dvar += std::pow(ds / opts_.assumedRange_m, 2);
        if (linear)
            dvar += turn * turn;  // which way it moves the folded angle is unknown
        else
            tr.angle = wrapAngle(tr.angle - turn);
    }
    else
        dvar += opts_.noOdometryRate * opts_.noOdometryRate * dt;
    tr.var += dvar;
    tr.t_s = t_s;
    tr.pose = pose;

    const double S = tr.var + sd * sd;
    const double gate = opts_.gateSigmas * std::sqrt(S);
    dec.predicted_rad = linear ? wrapAngle(broadside + tr.angle) : tr.angle;
    dec.trackStd_rad = std::sqrt(tr.var);
    dec.support = tr.hits;
    // An established track decides between the window's candidates; a narrow one is also
    // sure enough to widen the σ of a bearing it contradicts.
    const bool established = tr.hits >= opts_.minHits;
    dec.confident = established && std::sqrt(tr.var) <= opts_.maxTrackStd_rad;

    const double d0 = std::abs(difference(z0, tr.angle));
    size_t chosen = 0;
    double dc = d0;
    // Only a window that can't tell is swapped for the track's candidate. A sure window the
    // track contradicts is a miss: a track that had locked onto the wrong endfire would swap
    // every right window for the wrong one, and each swap would confirm it.
    if (established && d0 > gate && !windowIsSure)
        for (size_t k = 1; k < candidates.size(); ++k)
        {
            if (candidates[k].relativePower < opts_.minCandidatePower) continue;
            const double zk = toTrack(candidates[k].theta_rad);
            // Linear arrays: only the other endfire replaces a bearing near one endfire (a
            // track that followed a reflection must not overrule a clean central bearing).
            if (linear && (std::abs(z0) < opts_.endfireZone_rad ||
                           std::abs(zk) < opts_.endfireZone_rad || zk * z0 > 0))
                continue;
            const double d = std::abs(difference(zk, tr.angle));
            if (d < dc) dc = d, chosen = k;
        }
    if (dc > gate)
    {
        // Nothing the window supports fits the track.
        dec.miss = true;
        dec.disagreement_rad = d0;
        // A window that can't tell doesn't count against the track.
        if (windowIsSure) ++tr.misses;
        if (tr.misses >= opts_.maxMisses || (!established && windowIsSure))
        {
            // The track is lost (or was never sure): start over from the window.
            tr.angle = z0;
            tr.var = sd * sd;
            tr.hits = 1;
            tr.misses = 0;
            dec.confident = false;
        }
        return dec;
    }
    dec.chosen = chosen;
    dec.disagreement_rad = dc;
    const double z = toTrack(candidates[chosen].theta_rad);
    const double K = tr.var / S;
    tr.angle += K * difference(z, tr.angle);
    if (!linear) tr.angle = wrapAngle(tr.angle);
    tr.var *= 1 - K;
    ++tr.hits;
    tr.misses = 0;
    return dec;
}

}  // namespace mrpt_wifi::bearing
