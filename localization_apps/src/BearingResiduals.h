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

/** AoA at the robot: the transmitter (ap[0..1]) seen from the receive array, whose pose is the
 *  robot pose ⊕ a fixed offset (odometry since the node ⊕ sensor pose on the robot). With an
 *  alternative direction (and its mirror), the closest of all (a max-mixture). */
struct AoaResidual
{
    double ox, oy, oth, z, mirror, sigma;
    bool ambiguous;
    bool hasAlternative = false;
    double alternative = 0, alternativeMirror = 0;

    template <typename T>
    bool operator()(const T* pose, const T* ap, T* r) const
    {
        using std::atan2, std::cos, std::sin;
        const T c = cos(pose[2]), s = sin(pose[2]);
        const T sx = pose[0] + c * T(ox) - s * T(oy);
        const T sy = pose[1] + s * T(ox) + c * T(oy);
        const T pred = atan2(ap[1] - sy, ap[0] - sx) - pose[2] - T(oth);
        r[0] = closestCandidate(pred, z, ambiguous, mirror);
        if (hasAlternative)
        {
            using std::abs;
            const T other = closestCandidate(pred, alternative, ambiguous, alternativeMirror);
            if (abs(other) < abs(r[0])) r[0] = other;
        }
        r[0] /= T(sigma);
        return true;
    }
};

/** `b`'s AoA residual seen from the offset (ox, oy, oth) with the given σ; `alternatives`:
 *  with b's alternative direction, when it has one (GraphSlamOptions::useAoaAlternatives). */
inline AoaResidual aoaResidualOf(
    const BearingRecord& b, double ox, double oy, double oth, double sigma, bool alternatives)
{
    AoaResidual r{ox, oy, oth, b.aoa, b.aoaMirror, sigma, b.aoaAmbiguous};
    if (alternatives && b.hasAoaAlternative)
    {
        r.hasAlternative = true;
        r.alternative = b.aoaAlternative;
        r.alternativeMirror = b.aoaAmbiguous ? aoaAlternativeMirror(b) : b.aoaAlternative;
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

/** The robust loss by name ("cauchy", "huber", "none"), scale in units of σ. */
inline ceres::LossFunction* makeLoss(const std::string& name, double scale)
{
    if (name == "cauchy") return new ceres::CauchyLoss(scale);
    if (name == "huber") return new ceres::HuberLoss(scale);
    if (name == "none") return nullptr;
    throw std::invalid_argument("unknown robust loss '" + name + "' (cauchy, huber, none)");
}

}  // namespace mrpt_wifi::localization::detail
