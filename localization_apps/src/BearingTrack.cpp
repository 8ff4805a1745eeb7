/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt_wifi/localization/BearingTrack.h>
#include <mrpt_wifi/localization/DeviceMapper.h>
#include <mrpt_wifi/localization/IniValues.h>

#include <algorithm>
#include <array>
#include <limits>
#include <stdexcept>

#include "BearingResiduals.h"

namespace mrpt_wifi::localization
{
using mrpt::math::TPose2D;
using mrpt::math::wrapToPi;

void TrackMotionPrior::loadFromConfigFile(
    const mrpt::config::CConfigFileBase& c, const std::string& s)
{
    requireIniNumbers(
        c, s,
        {"track_node_period_s", "track_accel_std", "track_turn_accel_std_deg",
         "track_lateral_std_m"});
    nodePeriod_s = c.read_double(s, "track_node_period_s", nodePeriod_s);
    accelStd_mps2 = c.read_double(s, "track_accel_std", accelStd_mps2);
    turnAccelStd_radps2 = mrpt::DEG2RAD(
        c.read_double(s, "track_turn_accel_std_deg", mrpt::RAD2DEG(turnAccelStd_radps2)));
    lateralStd_m = c.read_double(s, "track_lateral_std_m", lateralStd_m);
    if (!(nodePeriod_s > 0) || !(accelStd_mps2 > 0) || !(turnAccelStd_radps2 > 0) ||
        !(lateralStd_m > 0))
        throw std::invalid_argument(
            "[" + s +
            "]: track_node_period_s, track_accel_std, track_turn_accel_std_deg and "
            "track_lateral_std_m must be > 0");
}

namespace
{
/** The step from node a to node b in a's frame: (forward, sideways, turn). */
template <typename T>
void relativeStep(const T* a, const T* b, T* d)
{
    using std::cos, std::sin;
    const T c = cos(a[2]), s = sin(a[2]);
    d[0] = c * (b[0] - a[0]) + s * (b[1] - a[1]);
    d[1] = -s * (b[0] - a[0]) + c * (b[1] - a[1]);
    d[2] = detail::wrapAngle(b[2] - a[2]);
}

/** Constant twist: two consecutive steps differ by little (σ per component). */
struct StepChangeResidual
{
    double sigmaXY, sigmaTurn;

    template <typename T>
    bool operator()(const T* a, const T* b, const T* c, T* r) const
    {
        T d1[3], d2[3];
        relativeStep(a, b, d1);
        relativeStep(b, c, d2);
        r[0] = (d2[0] - d1[0]) / T(sigmaXY);
        r[1] = (d2[1] - d1[1]) / T(sigmaXY);
        r[2] = detail::wrapAngle(d2[2] - d1[2]) / T(sigmaTurn);
        return true;
    }
};

/** Along the heading: the step's displacement across the mean heading of its two ends (an arc
 *  of a differential drive has none), and, forward only, its backward part. */
struct NonholonomicResidual
{
    double sigma;
    bool forwardOnly;

    template <typename T>
    bool operator()(const T* a, const T* b, T* r) const
    {
        using std::cos, std::sin;
        T d[3];
        relativeStep(a, b, d);
        const T half = d[2] / T(2);
        r[0] = (d[1] * cos(half) - d[0] * sin(half)) / T(sigma);
        const T along = d[0] * cos(half) + d[1] * sin(half);
        r[1] = forwardOnly && along < T(0) ? along / T(sigma) : T(0);
        return true;
    }
};

/** A bearing taken between two nodes: the graph's AoA or AoD residual at the pose
 *  interpolated at its time, the known transmitter fixed. */
struct InterpolatedBearingResidual
{
    double alpha;  // 0 at node a, 1 at node b
    detail::AoaResidual aoa;
    detail::AodResidual aod;
    bool departure;
    double ap[3];  // the transmitter: x, y, yaw

    template <typename T>
    bool operator()(const T* a, const T* b, T* r) const
    {
        const T pose[3] = {
            a[0] + T(alpha) * (b[0] - a[0]), a[1] + T(alpha) * (b[1] - a[1]),
            a[2] + T(alpha) * detail::wrapAngle(b[2] - a[2])};
        const T tx[3] = {T(ap[0]), T(ap[1]), T(ap[2])};
        return departure ? aod(pose, tx, r) : aoa(pose, tx, r);
    }
};

/** Outside the area: the distance beyond its edge, per axis. */
struct AreaResidual
{
    double minX, maxX, minY, maxY, sigma;

    template <typename T>
    bool operator()(const T* p, T* r) const
    {
        const auto beyond = [&](const T& v, double lo, double hi) {
            return v < T(lo) ? (v - T(lo)) / T(sigma) : v > T(hi) ? (v - T(hi)) / T(sigma) : T(0);
        };
        r[0] = beyond(p[0], minX, maxX);
        r[1] = beyond(p[1], minY, maxY);
        return true;
    }
};

/** `track` at `t`: interpolated, or its nearest end outside it. */
TPose2D poseAt(const Trajectory2D& track, double t)
{
    TPose2D p;
    if (track.interpolate(t, p, std::numeric_limits<double>::infinity())) return p;
    return t < track.t.front() ? track.poses.front() : track.poses.back();
}
}  // namespace

TrackResult solveBearingTrack(
    const TrackInput& in, const TrackMotionPrior& prior, const GraphSlamOptions& opt)
{
    const double h = prior.nodePeriod_s;
    if (!(in.t1 >= in.t0 + h))
        throw std::runtime_error("solveBearingTrack: the window is shorter than one node step");
    if (in.starts.empty() ||
        std::any_of(
            in.starts.begin(), in.starts.end(), [](const auto& s) { return s.size() == 0; }))
        throw std::runtime_error("solveBearingTrack: no start, or an empty one");
    std::vector<double> times;
    for (double t = in.t1; t >= in.t0 - 1e-9; t -= h) times.push_back(t);
    std::reverse(times.begin(), times.end());
    const size_t N = times.size();

    // Each usable bearing, once per angle, with its segment [k, k+1] and place in it.
    struct Use
    {
        const BearingRecord* b;
        const KnownTransmitter* tx;
        size_t k;
        double alpha;
        bool departure;
    };
    std::vector<Use> uses;
    for (const auto& b : in.bearings)
    {
        const auto* tx = in.aps.find(b.transmitter);
        if (!tx || b.t < times.front() || b.t > times.back()) continue;
        const size_t k = std::min(size_t((b.t - times.front()) / h), N - 2);
        const double alpha = std::clamp((b.t - times[k]) / h, 0.0, 1.0);
        if (opt.useAoa && b.hasAoa) uses.push_back({&b, tx, k, alpha, false});
        if (opt.useAod && b.hasAod) uses.push_back({&b, tx, k, alpha, true});
    }
    if (uses.empty()) throw std::runtime_error("solveBearingTrack: no usable bearing");

    const auto sigmaOf = [&](const Use& u)
    {
        const double reported = u.departure ? u.b->aodStd : aoaStdFor(*u.b, opt.useAoaAlternatives);
        return std::max(opt.minStd_rad, opt.stdScale * reported);
    };

    // Bearings taken close together share their multipath error (as in the graph), counted on
    // the first start's track: the same σ for every start, whose costs are compared.
    BearingDecorrelation decorrelation(opt.bearingDecorrelation_m);
    for (const auto& u : uses)
    {
        const auto p = poseAt(in.starts.front(), u.b->t);
        decorrelation.add(u.b->transmitter, p.x, p.y);
    }

    TrackResult best;
    best.finalCost = std::numeric_limits<double>::infinity();
    for (size_t si = 0; si < in.starts.size(); ++si)
    {
        const auto& start = in.starts[si];
        std::vector<std::array<double, 3>> X(N);
        for (size_t k = 0; k < N; ++k)
        {
            const auto p = poseAt(start, times[k]);
            X[k] = {p.x, p.y, p.phi};
        }
        ceres::Problem::Options po;
        po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
        ceres::Problem problem(po);
        std::vector<ceres::ResidualBlockId> bearingBlocks;
        for (const auto& u : uses)
        {
            const double sigma = sigmaOf(u) * decorrelation.factor(u.b->transmitter);
            const auto& b = *u.b;
            const auto& s = b.sensorPose;
            auto* r = new InterpolatedBearingResidual{
                u.alpha,
                detail::aoaResidualOf(
                    b, s.x, s.y, s.phi, sigma, opt.useAoaAlternatives,
                    detail::robustLossOf(opt.loss, opt.lossScale)),
                {s.x, s.y, b.aod, b.aodMirror, sigma, b.aodAmbiguous},
                u.departure,
                {u.tx->pose.x, u.tx->pose.y, u.tx->pose.phi}};
            bearingBlocks.push_back(problem.AddResidualBlock(
                new ceres::AutoDiffCostFunction<InterpolatedBearingResidual, 1, 3, 3>(r),
                detail::makeLoss(opt.loss, opt.lossScale), X[u.k].data(), X[u.k + 1].data()));
        }
        if (in.area)
            for (auto& x : X)
                problem.AddResidualBlock(
                    new ceres::AutoDiffCostFunction<AreaResidual, 2, 3>(new AreaResidual{
                        in.area->min.x, in.area->max.x, in.area->min.y, in.area->max.y, 0.05}),
                    nullptr, x.data());
        for (size_t k = 0; k + 1 < N; ++k)
        {
            problem.AddResidualBlock(
                new ceres::AutoDiffCostFunction<NonholonomicResidual, 2, 3, 3>(
                    new NonholonomicResidual{prior.lateralStd_m, prior.forwardOnly}),
                nullptr, X[k].data(), X[k + 1].data());
            if (k + 2 < N)
                problem.AddResidualBlock(
                    new ceres::AutoDiffCostFunction<StepChangeResidual, 3, 3, 3, 3>(
                        new StepChangeResidual{
                            prior.accelStd_mps2 * h * h, prior.turnAccelStd_radps2 * h * h}),
                    nullptr, X[k].data(), X[k + 1].data(), X[k + 2].data());
        }

        ceres::Solver::Options so;
        so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
        so.max_num_iterations = opt.maxIterations;
        so.num_threads = opt.threads;
        ceres::Solver::Summary sum;
        ceres::Solve(so, &problem, &sum);
        const double margin = si > 0 && best.start == 0 ? in.firstStartMargin : 0.0;
        if (!sum.IsSolutionUsable() || !(sum.final_cost < best.finalCost - margin)) continue;

        TrackResult r;
        r.finalCost = sum.final_cost;
        r.bearingEdges = uses.size();
        r.start = si;
        for (size_t k = 0; k < N; ++k)
            r.poses.push_back(times[k], TPose2D(X[k][0], X[k][1], wrapToPi(X[k][2])));
        std::vector<double> whitened;
        for (const auto id : bearingBlocks)
        {
            double cost = 0, res = 0;
            if (problem.EvaluateResidualBlock(id, false, &cost, &res, nullptr))
                whitened.push_back(std::abs(res));
        }
        r.medianWhitenedResidual = detail::median(std::move(whitened));
        best = std::move(r);
    }
    if (best.poses.size() == 0)
        throw std::runtime_error("solveBearingTrack: no start gave a usable solution");
    return best;
}

}  // namespace mrpt_wifi::localization
