/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// Ceres residuals shared by graph SLAM, the track without odometry, the window smoother and
// device mapping (internal header). Angles are compared on the circle: wrap(a) =
// atan2(sin a, cos a) keeps derivatives smooth. For linear arrays the residual uses whichever of
// the two reported candidates is closer to the prediction (the other one is the array's mirror
// image, equally consistent with the CSI).

#include <ceres/ceres.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/BearingRecord.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace mrpt_wifi::localization::detail
{
template <typename T>
T wrapAngle(const T& a)
{
    using std::atan2, std::cos, std::sin;
    return atan2(sin(a), cos(a));
}

/** The median of v (the upper one of an even count), 0 for none: how the solvers summarise
 *  their residuals. */
inline double median(std::vector<double> v)
{
    if (v.empty()) return 0;
    const auto mid = v.begin() + long(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

template <typename T>
T closestCandidate(const T& predicted, double z, bool ambiguous, double mirror)
{
    const T r1 = wrapAngle(predicted - T(z));
    if (!ambiguous) return r1;
    const T r2 = wrapAngle(predicted - T(mirror));
    using std::abs;
    return abs(r2) < abs(r1) ? r2 : r1;
}

/** SE(2) relative-pose edge (odometry), whitened by the square root of its information. The
 *  odometry's systematic errors are a parameter block shared by all edges: bias[0] scales the
 *  measured translation, bias[1] adds a heading change per metre travelled (dist). */
struct OdometryResidual
{
    double dx, dy, dth, dist;
    double sqrtInfo[9];  // row-major, upper-triangular Cholesky factor of the information

    template <typename T>
    bool operator()(const T* pi, const T* pj, const T* bias, T* r) const
    {
        using std::cos, std::sin;
        const T c = cos(pi[2]), s = sin(pi[2]);
        const T ex = c * (pj[0] - pi[0]) + s * (pj[1] - pi[1]) - bias[0] * T(dx);
        const T ey = -s * (pj[0] - pi[0]) + c * (pj[1] - pi[1]) - bias[0] * T(dy);
        const T et = wrapAngle(pj[2] - pi[2] - T(dth) - bias[1] * T(dist));
        const T e[3] = {ex, ey, et};
        for (int k = 0; k < 3; ++k)
            r[k] = T(sqrtInfo[3 * k]) * e[0] + T(sqrtInfo[3 * k + 1]) * e[1] +
                   T(sqrtInfo[3 * k + 2]) * e[2];
        return true;
    }
};

/** Prior on the odometry's systematic errors: scale 1 ± scaleStd, heading drift 0 ± yawStd
 *  [rad/m]. */
struct OdometryBiasPrior
{
    double scaleStd, yawStd;

    template <typename T>
    bool operator()(const T* bias, T* r) const
    {
        r[0] = (bias[0] - T(1)) / T(scaleStd);
        r[1] = bias[1] / T(yawStd);
        return true;
    }
};

/** The robust loss a bearing block gets (makeLoss), for max-mixtures that must weigh their
 *  components' penalties after it. */
struct RobustLoss
{
    enum Kind
    {
        None,
        Cauchy,
        Huber
    } kind = None;
    double scale = 1;  //!< a, in units of σ

    /** ρ(s) of a squared residual s, as Ceres's CauchyLoss / HuberLoss. */
    template <typename T>
    T apply(const T& s) const
    {
        using std::log, std::sqrt;
        const double a2 = scale * scale;
        if (kind == Cauchy) return T(a2) * log(T(1) + s / T(a2));
        if (kind == Huber) return s <= T(a2) ? s : T(2 * scale) * sqrt(s) - T(a2);
        return s;
    }
    /** The squared residual whose ρ is v. */
    template <typename T>
    T invert(const T& v) const
    {
        using std::exp;
        const double a2 = scale * scale;
        if (kind == Cauchy) return T(a2) * (exp(v / T(a2)) - T(1));
        if (kind == Huber)
        {
            if (v <= T(a2)) return v;
            const T root = (v + T(a2)) / T(2 * scale);
            return root * root;
        }
        return v;
    }
};

/** AoA at the robot: the transmitter (ap[0..1]) seen from the receive array, whose pose is the
 *  robot pose ⊕ a fixed offset (odometry since the node ⊕ sensor pose on the robot). With
 *  alternative directions (each with its mirror), a weighted max-mixture (Olson & Agarwal):
 *  the direction of least ρ((residual/σ)²) + 2·ln(w_max / w) counts, ρ the block's robust
 *  loss, so a lighter direction explains a pose only when it fits that much better; the
 *  penalty is added after the loss so that the loss, which caps what one bearing may cost,
 *  does not cap the weights too. */
struct AoaResidual
{
    static constexpr size_t kMaxDirections = 1 + 3;
    double ox, oy, oth, z, mirror, sigma;
    bool ambiguous;
    size_t alternatives = 0;  //!< directions beyond z
    double alternative[kMaxDirections - 1] = {}, alternativeMirror[kMaxDirections - 1] = {};
    /** 2·ln(w_max / w) of z and of each alternative (0 for the heaviest). */
    double penalty[kMaxDirections] = {};
    RobustLoss loss;  //!< the loss Ceres applies to this block

    template <typename T>
    bool operator()(const T* pose, const T* ap, T* r) const
    {
        using std::atan2, std::cos, std::sin, std::sqrt;
        const T c = cos(pose[2]), s = sin(pose[2]);
        const T sx = pose[0] + c * T(ox) - s * T(oy);
        const T sy = pose[1] + s * T(ox) + c * T(oy);
        const T pred = atan2(ap[1] - sy, ap[0] - sx) - pose[2] - T(oth);
        T best = closestCandidate(pred, z, ambiguous, mirror) / T(sigma);
        if (alternatives == 0)
        {
            r[0] = best;
            return true;
        }
        T bestCost = loss.apply(best * best) + T(penalty[0]);
        size_t bestIndex = 0;
        for (size_t i = 0; i < alternatives; ++i)
        {
            const T e =
                closestCandidate(pred, alternative[i], ambiguous, alternativeMirror[i]) / T(sigma);
            const T cost = loss.apply(e * e) + T(penalty[i + 1]);
            if (cost < bestCost) best = e, bestCost = cost, bestIndex = i + 1;
        }
        // The heaviest direction keeps its signed residual; a lighter one the residual whose
        // loss is its own plus its penalty.
        r[0] = penalty[bestIndex] > 0 ? sqrt(loss.invert(bestCost)) : best;
        return true;
    }
};

/** `b`'s AoA residual seen from the offset (ox, oy, oth) with the given σ; `alternatives`:
 *  with b's alternative directions, weighed as the estimator measured them
 *  (GraphSlamOptions::useAoaAlternatives). */
inline AoaResidual aoaResidualOf(
    const BearingRecord& b, double ox, double oy, double oth, double sigma, bool alternatives,
    const RobustLoss& loss = RobustLoss())
{
    AoaResidual r{ox, oy, oth, b.aoa, b.aoaMirror, sigma, b.aoaAmbiguous};
    r.loss = loss;
    if (!alternatives || !b.hasAoaAlternative) return r;
    const auto dirs = aoaDirections(b, 1.0);
    double heaviest = 0;
    for (const auto& d : dirs) heaviest = std::max(heaviest, d.weight);
    for (size_t i = 0; i < dirs.size() && i < AoaResidual::kMaxDirections; ++i)
    {
        r.penalty[i] = 2 * std::log(heaviest / std::max(dirs[i].weight, 1e-6));
        if (i == 0) continue;
        r.alternative[i - 1] = dirs[i].aoa;
        r.alternativeMirror[i - 1] = dirs[i].mirror;
        r.alternatives = i;
    }
    return r;
}

/** AoD at the transmitter (ap = x, y, yaw): direction of the receive array in its frame. */
struct AodResidual
{
    double ox, oy, z, mirror, sigma;
    bool ambiguous;

    template <typename T>
    bool operator()(const T* pose, const T* ap, T* r) const
    {
        using std::atan2, std::cos, std::sin;
        const T c = cos(pose[2]), s = sin(pose[2]);
        const T sx = pose[0] + c * T(ox) - s * T(oy);
        const T sy = pose[1] + s * T(ox) + c * T(oy);
        const T pred = atan2(sy - ap[1], sx - ap[0]) - ap[2];
        r[0] = closestCandidate(pred, z, ambiguous, mirror) / T(sigma);
        return true;
    }
};

/** AoA of a device at point p (2 parameters) from a known sensor pose. */
struct PointAoaResidual
{
    double sx, sy, sth, z, mirror, sigma;
    bool ambiguous;

    template <typename T>
    bool operator()(const T* p, T* r) const
    {
        using std::atan2;
        const T pred = atan2(p[1] - T(sy), p[0] - T(sx)) - T(sth);
        r[0] = closestCandidate(pred, z, ambiguous, mirror) / T(sigma);
        return true;
    }
};

/** The RobustLoss of makeLoss(name, scale). */
inline RobustLoss robustLossOf(const std::string& name, double scale)
{
    RobustLoss l;
    l.kind = name == "cauchy"  ? RobustLoss::Cauchy
             : name == "huber" ? RobustLoss::Huber
                               : RobustLoss::None;
    l.scale = scale;
    return l;
}

/** The robust loss by name ("cauchy", "huber", "none"), scale in units of σ. */
inline ceres::LossFunction* makeLoss(const std::string& name, double scale)
{
    if (name == "cauchy") return new ceres::CauchyLoss(scale);
    if (name == "huber") return new ceres::HuberLoss(scale);
    if (name == "none") return nullptr;
    throw std::invalid_argument("unknown robust loss '" + name + "' (cauchy, huber, none)");
}

}  // namespace mrpt_wifi::localization::detail
