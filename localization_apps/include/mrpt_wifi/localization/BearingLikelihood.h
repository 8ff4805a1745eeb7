/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/CMatrixFixed.h>
#include <mrpt/math/TPoint2D.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/TransmitterMap.h>

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace mrpt_wifi::localization
{
/** Robust measurement model of one bearing: a Gaussian on the wrapped residual mixed with a
 *  uniform density over the circle for outliers (multipath, wrong peaks),
 *  p(r) = (1 − ε)·N(r; 0, σ²) + ε/(2π), σ = max(σ_min, scale·σ_reported).
 *  Linear arrays report an unordered pair {θ, mirror}: p = ½·(p(r_θ) + p(r_mirror)). */
struct RobustBearingModel
{
    double outlierProb = 0.1;    //!< ε
    double minStd_rad = 0.0349;  //!< σ_min (2°)
    double stdScale = 1.0;       //!< inflates reported σ (errors are correlated in space)
    double maxStd_rad = 0.785;   //!< measurements with σ above this are ignored (45°)
    /** > 0: an AoA with alternative directions (BearingRecord::aoaAlternatives) is a mixture
     *  of its directions, each with its own σ (aoaDirectionStd), an alternative weighing this ×
     *  its weight (1: the weights as the estimator measured them) and the reported direction
     *  the rest; 0: one direction with the σ that reaches the ambiguous alternative (aoaStd). */
    double aoaAlternativeShare = 0;

    double sigma(double reportedStd) const { return std::max(minStd_rad, stdScale * reportedStd); }
    /** log p(r) for a wrapped residual r and effective σ. */
    double logLikelihood(double residual, double sigma) const
    {
        const double r = residual / sigma;
        return logOfInlierDensity(std::exp(-0.5 * r * r) / (sigma * 2.5066282746310002));
    }
    /** The Gaussian density of a measurement (averaged with its mirror if ambiguous) given the
     *  predicted angle, without the outliers. */
    static double inlierDensity(
        double predicted, double measured, bool ambiguous, double mirror, double sigma)
    {
        const auto g = [&](double z)
        {
            const double r = wrapToPi(predicted - z) / sigma;
            return std::exp(-0.5 * r * r);
        };
        return (ambiguous ? 0.5 * (g(measured) + g(mirror)) : g(measured)) /
               (sigma * 2.5066282746310002);
    }
    /** log p of a measurement whose Gaussian part has `density`: the outliers added. */
    double logOfInlierDensity(double density) const
    {
        return std::log((1 - outlierProb) * density + outlierProb * 0.15915494309189535);
    }
    /** log p of a measurement (and its mirror if ambiguous) given the predicted angle. */
    double logLikelihood(
        double predicted, double measured, bool ambiguous, double mirror, double sigma) const
    {
        return logOfInlierDensity(inlierDensity(predicted, measured, ambiguous, mirror, sigma));
    }
};

/** World pose of the receive array: robot pose ⊕ sensor pose (planar). */
inline mrpt::math::TPose2D sensorWorldPose(
    const mrpt::math::TPose2D& robot, const mrpt::math::TPose2D& sensorOnRobot)
{
    const double c = std::cos(robot.phi), s = std::sin(robot.phi);
    return {
        robot.x + c * sensorOnRobot.x - s * sensorOnRobot.y,
        robot.y + s * sensorOnRobot.x + c * sensorOnRobot.y, robot.phi + sensorOnRobot.phi};
}

/** Predicted AoA [rad] of a transmitter at (tx, ty) seen from a sensor at world pose `s`. */
inline double predictAoa(const mrpt::math::TPose2D& s, double tx, double ty)
{
    return wrapToPi(std::atan2(ty - s.y, tx - s.x) - s.phi);
}
/** Predicted AoD [rad]: direction of the sensor at (sx, sy) in the transmitter's frame. */
inline double predictAod(const mrpt::math::TPose2D& tx, double sx, double sy)
{
    return wrapToPi(std::atan2(sy - tx.y, sx - tx.x) - tx.phi);
}

/** Which angles of a record a consumer uses. */
struct BearingUse
{
    bool aoa = true;
    bool aod = true;
};

/** Whether a record has an angle the model weighs: one that `use` selects, with a σ of at most
 *  max_std. recordLogLikelihood() and recordAgrees() use only these angles. */
/** The mirror of `r`'s AoA alternative across the linear array's axis (which lies halfway
 *  between aoa and aoaMirror); meaningful when aoaAmbiguous. */
inline double aoaAlternativeMirror(const BearingRecord& r)
{
    return wrapToPi(r.aoa + r.aoaMirror - r.aoaAlternative);
}
/** The mirror of any direction `theta` of `r` across the linear array's axis (`theta` itself
 *  when r is not ambiguous). */
inline double aoaMirrorOf(const BearingRecord& r, double theta)
{
    return r.aoaAmbiguous ? wrapToPi(r.aoa + r.aoaMirror - theta) : theta;
}
/** One direction of a record's AoA mixture: angle, its mirror, weight. */
struct AoaDirection
{
    double aoa, mirror, weight;
};
/** `r`'s AoA directions with their weights: each alternative's weight × `share` (their sum at
 *  most kMaxAlternativesWeight), the reported direction the rest; only the reported one when
 *  `share` is 0 or r has no alternative. */
std::vector<AoaDirection> aoaDirections(const BearingRecord& r, double share);
/** Cap on the weight all of a record's alternatives together take from its reported
 *  direction (the estimator's weights are odds of each; a tracker's swap may add its own). */
constexpr double kMaxAlternativesWeight = 0.9;
/** Whether `model` weighs `r`'s AoA as a mixture of its two directions. */
inline bool usesAoaAlternative(const BearingRecord& r, const RobustBearingModel& model)
{
    return model.aoaAlternativeShare > 0 && r.hasAoaAlternative;
}
/** The reported σ of `r`'s AoA: each direction's own when `alternatives` are weighed and r
 *  has one, else the one that covers all. */
inline double aoaStdFor(const BearingRecord& r, bool alternatives)
{
    return alternatives && r.hasAoaAlternative ? r.aoaDirectionStd : r.aoaStd;
}
/** The reported σ `model` takes for `r`'s AoA (aoaStdFor). */
inline double aoaStdUsed(const BearingRecord& r, const RobustBearingModel& model)
{
    return aoaStdFor(r, model.aoaAlternativeShare > 0);
}
inline bool usesAoa(const BearingRecord& r, const RobustBearingModel& model, const BearingUse& use)
{
    return use.aoa && r.hasAoa && aoaStdUsed(r, model) <= model.maxStd_rad;
}
inline bool usesAod(const BearingRecord& r, const RobustBearingModel& model, const BearingUse& use)
{
    return use.aod && r.hasAod && r.aodStd <= model.maxStd_rad;
}
inline bool recordWeighed(
    const BearingRecord& r, const RobustBearingModel& model, const BearingUse& use)
{
    return usesAoa(r, model, use) || usesAod(r, model, use);
}
/** "use_aoa = …, use_aod = …, max_std_deg = …": the keys that decide recordWeighed(), for
 *  messages. */
std::string weighedAnglesString(const RobustBearingModel& model, const BearingUse& use);

/** log-likelihood of one record given the robot pose and the transmitter (AoA and/or AoD). */
double recordLogLikelihood(
    const BearingRecord& r, const mrpt::math::TPose2D& robot, const KnownTransmitter& tx,
    const RobustBearingModel& model, const BearingUse& use);

/** Whether a record agrees with a robot pose: every angle the model uses (as
 *  recordLogLikelihood() selects them) within `nSigma` effective σ of its prediction (either
 *  member of an ambiguous pair). std::nullopt when no angle is used. */
std::optional<bool> recordAgrees(
    const BearingRecord& r, const mrpt::math::TPose2D& robot, const KnownTransmitter& tx,
    const RobustBearingModel& model, const BearingUse& use, double nSigma = 3.0);

/** How often bearings fix a pose on their own: for each second of a recording, how many
 *  transmitters gave it a sharp bearing (an angle `use` selects, reported σ at most
 *  `sharpStd_rad`). Without odometry a pose (x, y, heading) needs three such transmitters at
 *  once: with fewer only the motion between seconds can fix it, and a room whose seconds mostly
 *  have fewer leaves a filter without odometry little to find the robot by. */
struct SharpCoverage
{
    /** Seconds from the first bearing's to the last's, by the number of transmitters with a
     *  sharp bearing in them: 0, 1, 2, 3 or more. */
    std::array<size_t, 4> secondsWith{};
    size_t seconds() const;
    /** Share of the seconds with at least `transmitters` (1..3) sharp; NaN without seconds. */
    double shareWithAtLeast(size_t transmitters) const;
    /** "3+ transmitters with a sharp bearing in 35 % of 40 s (2: 50 %, 1: 8 %, 0: 8 %)". */
    std::string asString() const;
};
SharpCoverage sharpCoverage(
    const std::vector<BearingRecord>& records, const BearingUse& use, double sharpStd_rad);

/** Covariance of (x, y, φ) [m², rad²] that a bias of `biasStd_rad` per transmitter and angle,
 *  common to all its bearings (multipath seen alike from nearby poses, which no number of
 *  bearings averages out), leaves in a robot pose fixed by them: the inverse Fisher information
 *  of one bearing per transmitter and angle in `use` (AoA: direction and heading; AoD:
 *  direction only) at `robot` (the array's offset on the robot included), with a weak prior of
 *  `priorStd_m` and π on the pose so that a geometry that does not fix it (too few
 *  transmitters, all in line) gives a large but finite covariance. Its position block grows
 *  where the transmitters are seen under small angles (two side by side, all far away): what a
 *  particle cloud does not know when its bearings agree with each other. */
mrpt::math::CMatrixDouble33 bearingBiasCovariance(
    const mrpt::math::TPose2D& robot, const mrpt::math::TPose2D& sensorOnRobot,
    const std::vector<mrpt::math::TPoint2D>& transmitters, const BearingUse& use,
    double biasStd_rad, double priorStd_m);

}  // namespace mrpt_wifi::localization
