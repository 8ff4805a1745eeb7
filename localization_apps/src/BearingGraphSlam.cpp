/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPosePDFGaussianInf.h>
#include <mrpt/system/CTicTac.h>
#include <mrpt_wifi/localization/BearingGraphSlam.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/DeviceMapper.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "BearingResiduals.h"

namespace mrpt_wifi::localization
{
using mrpt::math::TPose2D;

namespace
{
TPose2D compose(const TPose2D& a, const TPose2D& b)
{
    const double c = std::cos(a.phi), s = std::sin(a.phi);
    return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, wrapToPi(a.phi + b.phi)};
}
TPose2D inverseCompose(const TPose2D& a, const TPose2D& b)  // a⁻¹ ⊕ b
{
    const double c = std::cos(a.phi), s = std::sin(a.phi);
    const double dx = b.x - a.x, dy = b.y - a.y;
    return {c * dx + s * dy, -s * dx + c * dy, wrapToPi(b.phi - a.phi)};
}

struct UnionFind
{
    std::vector<size_t> p;
    explicit UnionFind(size_t n) : p(n) { std::iota(p.begin(), p.end(), 0); }
    size_t find(size_t x) { return p[x] == x ? x : p[x] = find(p[x]); }
    void unite(size_t a, size_t b) { p[find(a)] = find(b); }
};

/** Where the time of one solveBearingGraph call goes (GraphSlamResult::phases) and its progress
 *  lines (GraphSlamOptions::progress), each with the time elapsed since the call started. */
class PhaseLog
{
public:
    explicit PhaseLog(const GraphSlamOptions& o)
        : progress_(o.progress), phaseFinished_(o.phaseFinished)
    {
    }

    void add(const std::string& name, double seconds)
    {
        if (phaseFinished_) phaseFinished_(GraphSlamPhase{name, seconds, 1});
        auto it = std::find_if(
            phases.begin(), phases.end(), [&](const GraphSlamPhase& p) { return p.name == name; });
        if (it == phases.end()) it = phases.insert(phases.end(), GraphSlamPhase{name, 0, 0});
        it->seconds += seconds;
        it->runs++;
    }
    void say(const std::string& line)
    {
        lastSaid_ = clock_.Tac();
        if (!progress_) return;
        std::ostringstream s;
        s << "[" << std::fixed << std::setprecision(1) << lastSaid_ << " s] " << line;
        progress_(s.str());
    }
    double elapsed() const { return clock_.Tac(); }
    double sinceLastLine() const { return clock_.Tac() - lastSaid_; }
    void copyTo(GraphSlamResult& r) const
    {
        r.phases = phases;
        r.apTriangulations = triangulations;
    }

    std::vector<GraphSlamPhase> phases;
    size_t triangulations = 0;

private:
    std::function<void(const std::string&)> progress_;
    std::function<void(const GraphSlamPhase&)> phaseFinished_;
    mrpt::system::CTicTac clock_;
    double lastSaid_ = 0;
};

/** Times one phase from construction to stop() (or destruction). */
class PhaseTimer
{
public:
    PhaseTimer(PhaseLog& log, std::string name) : log_(log), name_(std::move(name)) {}
    ~PhaseTimer() { stop(); }
    PhaseTimer(const PhaseTimer&) = delete;
    PhaseTimer& operator=(const PhaseTimer&) = delete;
    double stop()
    {
        if (!running_) return 0;
        running_ = false;
        const double s = tic_.Tac();
        log_.add(name_, s);
        return s;
    }

private:
    PhaseLog& log_;
    std::string name_;
    mrpt::system::CTicTac tic_;
    bool running_ = true;
};

std::string secondsText(double s)
{
    std::ostringstream o;
    o << std::fixed << std::setprecision(s < 10 ? 2 : 1) << s << " s";
    return o.str();
}
}  // namespace

TPose2D placeTrajectory(
    const Trajectory2D& odo, const std::vector<BearingRecord>& bearings, const TransmitterMap& aps,
    double window_s)
{
    return placeTrajectoryCandidates(odo, bearings, aps, window_s, 1).front();
}

std::vector<TPose2D> placeTrajectoryCandidates(
    const Trajectory2D& odo, const std::vector<BearingRecord>& bearings, const TransmitterMap& aps,
    double window_s, size_t maxCandidates)
{
    if (odo.empty()) throw std::runtime_error("placeTrajectory: empty odometry");
    struct Sample
    {
        const BearingRecord* b;
        TPose2D pose;  // odometry frame
        const KnownTransmitter* ap;
    };
    std::vector<Sample> sample;
    std::vector<const BearingRecord*> cand;
    for (const auto& b : bearings)
        if (b.t <= odo.t.front() + window_s && aps.find(b.transmitter)) cand.push_back(&b);
    const size_t stride = std::max<size_t>(1, cand.size() / 300);
    for (size_t i = 0; i < cand.size(); i += stride)
    {
        TPose2D p;
        if (odo.interpolate(cand[i]->t, p))
            sample.push_back({cand[i], p, aps.find(cand[i]->transmitter)});
    }
    if (sample.size() < 5)
        throw std::runtime_error(
            "cannot place the trajectory among the known APs: fewer than 5 bearings of known APs "
            "in the first " +
            std::to_string(int(window_s)) + " s of odometry");
    RobustBearingModel model;
    model.minStd_rad = 0.087;  // coarse grid: be tolerant
    const BearingUse use;
    // The score of a placement over every `every`-th sample.
    auto scoreWith = [&](const TPose2D& T, const RobustBearingModel& m, size_t every)
    {
        double ll = 0;
        for (size_t i = 0; i < sample.size(); i += every)
            ll += recordLogLikelihood(
                *sample[i].b, compose(T, sample[i].pose), *sample[i].ap, m, use);
        return ll;
    };
    auto score = [&](const TPose2D& T) { return scoreWith(T, model, 1); };
    double xmin, xmax, ymin, ymax;
    aps.bounds(0, xmin, xmax, ymin, ymax);
    // The trajectory starts somewhere among the APs: place its first pose there.
    const TPose2D p0 = odo.poses.front();
    auto transformFor = [&](double x, double y, double yaw)
    {
        // T such that T ⊕ p0 = (x, y, yaw)
        const double th = wrapToPi(yaw - p0.phi);
        const double c = std::cos(th), s = std::sin(th);
        return TPose2D(x - (c * p0.x - s * p0.y), y - (s * p0.x + c * p0.y), th);
    };
    struct Cell
    {
        double score, x, y, yaw;
    };
    const auto byScore = [](const Cell& a, const Cell& b) { return a.score > b.score; };
    // The global grid: 0.5 m and 5°, as long as that is at most kGridCells positions (a room);
    // over a larger area (a building) first a coarser grid with every third sample and σ
    // widened by its cells (a cell holds points up to 0.7 step from its centre), whose best
    // kCoarseModes cells are then searched at 0.5 m: the cost stays that of a room.
    constexpr double kFineStep = 0.5, kGridCells = 2500;
    constexpr size_t kCoarseModes = 12;
    const double area = std::max(xmax - xmin, kFineStep) * std::max(ymax - ymin, kFineStep);
    const double coarseStep = std::max(kFineStep, std::sqrt(area / kGridCells));
    std::vector<Cell> grid;
    if (coarseStep <= kFineStep)
    {
        for (double x = xmin; x <= xmax + 1e-9; x += kFineStep)
            for (double y = ymin; y <= ymax + 1e-9; y += kFineStep)
                for (int k = 0; k < 72; ++k)
                {
                    const double yaw = -M_PI + k * (M_PI / 36);
                    grid.push_back({score(transformFor(x, y, yaw)), x, y, yaw});
                }
    }
    else
    {
        RobustBearingModel coarse = model;
        coarse.minStd_rad = model.minStd_rad * coarseStep / kFineStep;
        std::vector<Cell> cells;
        for (double x = xmin; x <= xmax + 1e-9; x += coarseStep)
            for (double y = ymin; y <= ymax + 1e-9; y += coarseStep)
                for (int k = 0; k < 72; ++k)
                {
                    const double yaw = -M_PI + k * (M_PI / 36);
                    cells.push_back({scoreWith(transformFor(x, y, yaw), coarse, 3), x, y, yaw});
                }
        std::sort(cells.begin(), cells.end(), byScore);
        std::vector<Cell> coarseModes;
        for (const auto& c : cells)
        {
            if (coarseModes.size() >= kCoarseModes) break;
            bool near = false;
            for (const auto& m : coarseModes)
                near |= std::hypot(c.x - m.x, c.y - m.y) < 1.5 * coarseStep &&
                        std::abs(wrapToPi(c.yaw - m.yaw)) < M_PI / 4;
            if (!near) coarseModes.push_back(c);
        }
        const int n = int(std::ceil(0.5 * coarseStep / kFineStep));
        for (const auto& m : coarseModes)
            for (int i = -n; i <= n; ++i)
                for (int j = -n; j <= n; ++j)
                    for (int k = -1; k <= 1; ++k)
                    {
                        const double x = m.x + i * kFineStep, y = m.y + j * kFineStep;
                        const double yaw = wrapToPi(m.yaw + k * (M_PI / 36));
                        grid.push_back({score(transformFor(x, y, yaw)), x, y, yaw});
                    }
    }
    std::sort(grid.begin(), grid.end(), byScore);
    // Distinct modes, best first: a cell joins only if no better one is within 1.5 m and 45°.
    std::vector<Cell> modes;
    for (const auto& c : grid)
    {
        if (modes.size() >= std::max<size_t>(1, maxCandidates)) break;
        bool near = false;
        for (const auto& m : modes)
            near |= std::hypot(c.x - m.x, c.y - m.y) < 1.5 &&
                    std::abs(wrapToPi(c.yaw - m.yaw)) < M_PI / 4;
        if (!near) modes.push_back(c);
    }
    std::vector<std::pair<double, TPose2D>> refined;
    for (const auto& m : modes)
    {
        double best = -1e300;
        TPose2D bestT;
        for (double x = m.x - 0.5; x <= m.x + 0.5 + 1e-9; x += 0.1)
            for (double y = m.y - 0.5; y <= m.y + 0.5 + 1e-9; y += 0.1)
                for (int k = -5; k <= 5; ++k)
                {
                    const TPose2D T = transformFor(x, y, m.yaw + k * M_PI / 180);
                    const double s = score(T);
                    if (s > best) best = s, bestT = T;
                }
        refined.emplace_back(best, bestT);
    }
    std::stable_sort(
        refined.begin(), refined.end(),
        [](const auto& a, const auto& b) { return a.first > b.first; });
    std::vector<TPose2D> out;
    for (const auto& r : refined) out.push_back(r.second);
    return out;
}

namespace
{
/** How one solve fits into the whole run: its progress line, and for the stages of the grown
 *  start the poses held where the previous stage left them and the APs carried over from it. */
struct SolveContext
{
    PhaseLog& log;
    std::string label;  //!< progress line after the solve; empty: none (grown stages)
    /** Nodes before this time stay at their initial poses (a grown stage solves its newest
     *  windows; the older ones were solved before): their odometry edges are left out, and so
     *  are their bearings of known APs. */
    double freeFrom = -std::numeric_limits<double>::infinity();
    /** Unknown APs solved by the previous stage: their start, unless their bearings have
     *  doubled since they were last triangulated (triangulatedWith). */
    const TransmitterMap* carriedAps = nullptr;
    std::map<MacAddress, size_t>* triangulatedWith = nullptr;
    int maxIterations = 0;  //!< > 0: instead of GraphSlamOptions::maxIterations
    /** The whole problem from a grown start: thousands of poses each a little off move the
     *  cost by less than Ceres' default relative tolerance (1e-6) per iteration while the
     *  trajectory still improves (a 15-minute drive: p90 0.065 -> 0.057 m): go on to 1e-10. */
    bool finalOfGrown = false;
};

/** One solve. The nodes start at `initialWorld` (interpolated at the node times) if given, else
 *  at the odometry composed with `place`; unknown APs are triangulated on those poses. */
GraphSlamResult solveOnce(
    const GraphSlamInput& in, const GraphSlamOptions& opt, const TPose2D& place,
    const Trajectory2D* initialWorld, SolveContext ctx)
{
    mrpt::system::CTicTac total;
    GraphSlamResult res;
    PhaseTimer attachTimer(ctx.log, "attach bearings to nodes");
    const Trajectory2D& odo = in.odometry;
    if (odo.size() < 2) throw std::runtime_error("graph SLAM: the odometry has < 2 poses");

    // ---- Pose nodes.
    Trajectory2D nodes;            // node times and initial poses (odometry frame)
    std::vector<size_t> graphIds;  // .graph node IDs in order
    if (in.graph)
    {
        if (in.graph->nodes.empty()) throw std::runtime_error("graph SLAM: empty .graph");
        if (in.graph->nodes.size() != odo.size())
            throw std::runtime_error(
                "graph SLAM: the .graph has " + std::to_string(in.graph->nodes.size()) +
                " nodes but the node-times file " + std::to_string(odo.size()) + " rows");
        size_t k = 0;
        for (const auto& [id, p] : in.graph->nodes)
        {
            graphIds.push_back(id);
            nodes.push_back(odo.t[k++], p.asTPose());
        }
    }
    else
    {
        for (size_t i = 0; i < odo.size(); ++i)
            if (nodes.empty() || odo.t[i] - nodes.t.back() >= opt.nodePeriod_s - 1e-9 ||
                i + 1 == odo.size())
                nodes.push_back(odo.t[i], odo.poses[i]);
    }
    const size_t N = nodes.size();
    // Odometry interpolation source: fine odometry, or the graph's own node poses.
    const Trajectory2D& interp = in.graph ? nodes : odo;

    // ---- APs.
    std::map<MacAddress, size_t> apIndex;
    std::vector<KnownTransmitter> apList;
    if (opt.apsKnown)
    {
        if (in.aps.empty()) throw std::runtime_error("graph SLAM: known APs requested, none given");
        for (const auto& t : in.aps.transmitters())
            apIndex[t.mac] = apList.size(), apList.push_back(t);
    }

    // ---- Attach bearings to nodes.
    struct Attached
    {
        const BearingRecord* b;
        size_t node;
        TPose2D offset;  // node ⊕ offset = receive array pose
    };
    std::vector<Attached> att;
    std::map<MacAddress, size_t> unknownSeen;
    for (const auto& b : in.bearings)
    {
        if (opt.apsKnown && !apIndex.count(b.transmitter))
        {
            res.warnings.unknownTransmitter++;
            continue;
        }
        TPose2D pb;
        if (b.t < nodes.t.front() || b.t > nodes.t.back() || !interp.interpolate(b.t, pb))
        {
            res.warnings.outsideTrajectory++;
            continue;
        }
        auto it = std::upper_bound(nodes.t.begin(), nodes.t.end(), b.t);
        const size_t k = size_t(it - nodes.t.begin()) - 1;
        TPose2D pk;
        interp.interpolate(nodes.t[k], pk);
        att.push_back({&b, k, compose(inverseCompose(pk, pb), b.sensorPose)});
        if (!opt.apsKnown) unknownSeen[b.transmitter]++;
    }
    if (att.empty())
        throw std::runtime_error(
            "graph SLAM: no usable bearings (" + res.warnings.summary() +
            "); do the bearings' timestamps overlap the odometry?");

    attachTimer.stop();
    // ---- Initial values.
    std::vector<std::array<double, 3>> X(N);
    for (size_t k = 0; k < N; ++k)
    {
        const TPose2D placedOdo = compose(place, nodes.poses[k]);
        TPose2D p = placedOdo;
        if (initialWorld && !initialWorld->interpolate(nodes.t[k], p))
            throw std::logic_error("graph SLAM: initial poses don't cover the nodes");
        X[k] = {p.x, p.y, p.phi};
        res.initialPoses.push_back(nodes.t[k], placedOdo);
    }
    if (!opt.apsKnown)
    {
        PhaseTimer initTimer(ctx.log, "unknown-AP initialisation");
        // Unknown APs: triangulate each from its AoA rays on the odometry trajectory, then its
        // yaw from AoD by voting over both mirror candidates.
        std::map<MacAddress, std::vector<BearingRay>> rays;
        // The rays start from the initial poses: the odometry, or (grown start) the poses
        // solved so far continued by the odometry.
        auto initialPose = [&](size_t k) { return TPose2D(X[k][0], X[k][1], X[k][2]); };
        for (const auto& a : att)
        {
            if (!a.b->hasAoa) continue;
            const auto s = compose(initialPose(a.node), a.offset);
            BearingRay r;
            r.x = s.x, r.y = s.y, r.sensorYaw = s.phi, r.aoa = a.b->aoa;
            r.mirror = a.b->aoaMirror, r.ambiguous = a.b->aoaAmbiguous, r.sigma = a.b->aoaStd;
            rays[a.b->transmitter].push_back(r);
        }
        DeviceMapOptions dmo;
        dmo.model.minStd_rad = std::max(opt.minStd_rad, 0.087);  // drifted rays: be tolerant
        dmo.gridStep_m = 0.25;
        for (const auto& [mac, count] : unknownSeen)
        {
            KnownTransmitter t;
            t.mac = mac;
            const KnownTransmitter* k = in.aps.find(mac);
            t.name = k ? k->name : mac.asString();
            t.array = k ? k->array : ArrayGeometry::fromElements({});
            const auto r = rays.find(mac);
            if (r == rays.end())
            {
                res.warnings.noAngle++;
                continue;  // AoD only: can't place it
            }
            // The previous stage's solution of this AP is a better start than rays from a
            // trajectory continued by odometry, until its bearings have doubled.
            const KnownTransmitter* carried = ctx.carriedAps ? ctx.carriedAps->find(mac) : nullptr;
            if (carried && ctx.triangulatedWith)
            {
                const auto last = ctx.triangulatedWith->find(mac);
                if (last != ctx.triangulatedWith->end() && count < 2 * last->second)
                {
                    t.pose = carried->pose;
                    apIndex[mac] = apList.size();
                    apList.push_back(t);
                    continue;
                }
            }
            const auto d = triangulateDevice(r->second, dmo);
            ctx.log.triangulations++;
            if (ctx.triangulatedWith) (*ctx.triangulatedWith)[mac] = count;
            if (!d.localized) continue;
            t.pose = TPose2D(d.x, d.y, 0);
            // Yaw: histogram of (direction to robot − AoD) over both candidates.
            std::vector<double> hist(360, 0);
            for (const auto& a : att)
            {
                if (a.b->transmitter != mac || !a.b->hasAod) continue;
                const auto s = compose(initialPose(a.node), a.offset);
                const double dir = std::atan2(s.y - d.y, s.x - d.x);
                for (int c = 0; c < (a.b->aodAmbiguous ? 2 : 1); ++c)
                {
                    const double yaw = wrapToPi(dir - (c ? a.b->aodMirror : a.b->aod));
                    hist[size_t(std::floor((yaw + M_PI) / (2 * M_PI) * 360)) % 360] += 1;
                }
            }
            double bestH = -1;
            for (size_t i = 0; i < 360; ++i)
            {
                const double h = hist[i] + 0.5 * (hist[(i + 1) % 360] + hist[(i + 359) % 360]);
                if (h > bestH) bestH = h, t.pose.phi = wrapToPi(-M_PI + (i + 0.5) * M_PI / 180);
            }
            apIndex[mac] = apList.size();
            apList.push_back(t);
        }
        if (apList.empty())
            throw std::runtime_error("graph SLAM: no AP could be initialised from the bearings");
    }
    std::vector<std::array<double, 3>> A(apList.size());
    for (size_t j = 0; j < apList.size(); ++j)
        A[j] = {apList[j].pose.x, apList[j].pose.y, apList[j].pose.phi};
    PhaseTimer buildTimer(ctx.log, "graph construction");

    // ---- The problem.
    ceres::Problem::Options po;
    po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    // Nodes before ctx.freeFrom are held (a grown stage's older windows).
    const size_t firstFree =
        size_t(std::lower_bound(nodes.t.begin(), nodes.t.end(), ctx.freeFrom) - nodes.t.begin());
    for (auto& x : X) problem.AddParameterBlock(x.data(), 3);
    for (size_t k = 0; k < firstFree && k < N; ++k) problem.SetParameterBlockConstant(X[k].data());
    for (auto& a : A) problem.AddParameterBlock(a.data(), 3);

    // The odometry's scale and heading drift per metre: estimated with their priors, or held at
    // "none" (a constant block).
    std::array<double, 2> odoBias = {1.0, 0.0};
    problem.AddParameterBlock(odoBias.data(), 2);
    const bool estimateBias = opt.odoScaleStd > 0 || opt.odoYawDriftStd_radPerM > 0;
    if (estimateBias)
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<detail::OdometryBiasPrior, 2, 2>(
                new detail::OdometryBiasPrior{
                    std::max(opt.odoScaleStd, 1e-9), std::max(opt.odoYawDriftStd_radPerM, 1e-9)}),
            nullptr, odoBias.data());
    else
        problem.SetParameterBlockConstant(odoBias.data());

    UnionFind uf(N);
    for (size_t k = 1; k < firstFree && k < N; ++k) uf.unite(k, 0);
    auto addOdo = [&](size_t i, size_t j, const TPose2D& z, const Eigen::Matrix3d& info)
    {
        Eigen::LLT<Eigen::Matrix3d> llt(info);
        if (llt.info() != Eigen::Success)
            throw std::runtime_error("graph SLAM: an odometry edge's information isn't positive");
        const Eigen::Matrix3d U = llt.matrixU();
        auto* r = new detail::OdometryResidual{z.x, z.y, z.phi, std::hypot(z.x, z.y), {}};
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) r->sqrtInfo[3 * a + b] = U(a, b);
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<detail::OdometryResidual, 3, 3, 3, 2>(r), nullptr,
            X[i].data(), X[j].data(), odoBias.data());
        uf.unite(i, j);
        res.odometryEdges++;
    };
    if (in.graph)
    {
        std::map<size_t, size_t> idx;
        for (size_t k = 0; k < graphIds.size(); ++k) idx[graphIds[k]] = k;
        for (const auto& [ids, e] : in.graph->edges)
        {
            const auto a = idx.find(ids.first), b = idx.find(ids.second);
            if (a == idx.end() || b == idx.end())
                throw std::runtime_error("graph SLAM: an edge of the .graph names a missing node");
            Eigen::Matrix3d info;
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) info(r, c) = e.cov_inv(r, c);
            addOdo(a->second, b->second, e.mean.asTPose(), info);
        }
    }
    else
    {
        for (size_t k = firstFree > 0 ? firstFree - 1 : 0; k + 1 < N; ++k)
        {
            const TPose2D z = inverseCompose(nodes.poses[k], nodes.poses[k + 1]);
            const double d = std::hypot(z.x, z.y);
            const double sxy = std::max(opt.odoSigmaXY_min, opt.odoSigmaXY_perSqrtM * std::sqrt(d));
            const double sth = std::max(
                opt.odoSigmaYaw_min, opt.odoSigmaYaw_perSqrtM * std::sqrt(d) +
                                         opt.odoSigmaYaw_perSqrtRad * std::sqrt(std::abs(z.phi)));
            Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
            info(0, 0) = info(1, 1) = 1 / (sxy * sxy);
            info(2, 2) = 1 / (sth * sth);
            addOdo(k, k + 1, z, info);
        }
    }
    for (size_t k = 1; k < N; ++k)
        if (uf.find(k) != uf.find(0))
            throw std::runtime_error(
                "graph SLAM: the pose graph is not connected (node " + std::to_string(k) +
                " has no odometry path to node 0)");

    auto sigma = [&](double s) { return std::max(opt.minStd_rad, opt.stdScale * s); };
    // Bearings taken close together share their multipath error.
    BearingDecorrelation decorrelation(opt.bearingDecorrelation_m);
    for (const auto& a : att)
    {
        const auto s = compose(TPose2D(X[a.node][0], X[a.node][1], X[a.node][2]), a.offset);
        decorrelation.add(a.b->transmitter, s.x, s.y);
    }
    const auto decorrelated = [&](const BearingRecord& b, double s)
    { return sigma(s) * decorrelation.factor(b.transmitter); };
    const auto aoaStd = [&](const BearingRecord& b)
    { return aoaStdFor(b, opt.useAoaAlternatives); };
    std::vector<bool> apUsed(A.size(), false), apAod(A.size(), false);
    std::vector<std::pair<ceres::ResidualBlockId, double>> bearingBlocks;  // with σ
    for (const auto& a : att)
    {
        const auto it = apIndex.find(a.b->transmitter);
        if (it == apIndex.end()) continue;  // an unknown AP that couldn't be initialised
        if (opt.apsKnown && a.node < firstFree) continue;  // pose and AP both held
        double* ap = A[it->second].data();
        if (opt.useAoa && a.b->hasAoa)
        {
            bearingBlocks.emplace_back(
                problem.AddResidualBlock(
                    new ceres::AutoDiffCostFunction<detail::AoaResidual, 1, 3, 3>(
                        new detail::AoaResidual(detail::aoaResidualOf(
                            *a.b, a.offset.x, a.offset.y, a.offset.phi,
                            decorrelated(*a.b, aoaStd(*a.b)), opt.useAoaAlternatives,
                            detail::robustLossOf(opt.loss, opt.lossScale)))),
                    detail::makeLoss(opt.loss, opt.lossScale), X[a.node].data(), ap),
                decorrelated(*a.b, aoaStd(*a.b)));
            res.aoaEdges++;
            apUsed[it->second] = true;
        }
        if (opt.useAod && a.b->hasAod)
        {
            bearingBlocks.emplace_back(
                problem.AddResidualBlock(
                    new ceres::AutoDiffCostFunction<detail::AodResidual, 1, 3, 3>(
                        new detail::AodResidual{
                            a.offset.x, a.offset.y, a.b->aod, a.b->aodMirror,
                            decorrelated(*a.b, a.b->aodStd), a.b->aodAmbiguous}),
                    detail::makeLoss(opt.loss, opt.lossScale), X[a.node].data(), ap),
                decorrelated(*a.b, a.b->aodStd));
            res.aodEdges++;
            apUsed[it->second] = apAod[it->second] = true;
        }
    }
    if (res.aoaEdges + res.aodEdges == 0)
        throw std::runtime_error("graph SLAM: no bearing edge (AoA and AoD both disabled?)");
    for (size_t j = 0; j < A.size(); ++j)
    {
        if (!apUsed[j]) res.apsWithoutBearings++;
        if (opt.apsKnown || !apUsed[j])
            problem.SetParameterBlockConstant(A[j].data());
        else if (!apAod[j])  // AoA only: the AP's yaw is unobservable, keep it out
            problem.SetManifold(A[j].data(), new ceres::SubsetManifold(3, {2}));
    }
    if (!opt.apsKnown) problem.SetParameterBlockConstant(X[0].data());  // gauge

    ceres::Solver::Options so;
    so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    so.max_num_iterations = ctx.maxIterations > 0 ? ctx.maxIterations : opt.maxIterations;
    so.num_threads = opt.threads;
    so.minimizer_progress_to_stdout = opt.verbose;
    if (ctx.finalOfGrown) so.function_tolerance = 1e-10;
    ceres::Solver::Summary sum;
    buildTimer.stop();
    PhaseTimer solveTimer(ctx.log, "Ceres solve");
    ceres::Solve(so, &problem, &sum);
    res.solveTime_s = solveTimer.stop();
    res.initialCost = sum.initial_cost, res.finalCost = sum.final_cost;
    res.iterations = int(sum.iterations.size());
    res.converged = sum.termination_type == ceres::CONVERGENCE;
    res.solverReport = sum.BriefReport();
    res.odometryScale = odoBias[0], res.odometryYawDrift_radPerM = odoBias[1];
    if (!sum.IsSolutionUsable()) throw std::runtime_error("Ceres failed: " + sum.BriefReport());
    if (!ctx.label.empty())
    {
        std::ostringstream line;
        line << "solved " << ctx.label << ": " << N << " poses, " << A.size() << " APs, "
             << res.aoaEdges + res.aodEdges << " bearing edges, " << res.iterations
             << " iterations, cost " << std::setprecision(4) << res.initialCost << " -> "
             << res.finalCost << " in " << secondsText(res.solveTime_s)
             << (res.converged ? "" : " (not converged)");
        ctx.log.say(line.str());
    }

    // ---- How far the bearings are from the solution: biased bearings (e.g. a receiver
    //      calibration of another boot) stay tens of degrees off whatever the start.
    {
        PhaseTimer residualTimer(ctx.log, "residual statistics");
        std::vector<double> w, deg;
        w.reserve(bearingBlocks.size()), deg.reserve(bearingBlocks.size());
        size_t within = 0;
        for (const auto& [id, sg] : bearingBlocks)
        {
            double cost = 0, r = 0;
            if (!problem.EvaluateResidualBlock(id, false, &cost, &r, nullptr)) continue;
            w.push_back(std::abs(r));
            deg.push_back(mrpt::RAD2DEG(std::abs(r) * sg));
            within += std::abs(r) <= 3;
        }
        if (!w.empty())
        {
            res.bearingsWithin3Sigma = double(within) / double(w.size());
            res.medianWhitenedResidual = detail::median(w);
            res.medianResidual_deg = detail::median(deg);
        }
    }

    // ---- AP position covariance from the joint solution (trajectory and APs together).
    res.apCov.assign(A.size(), {0, 0, 0});
    if (opt.apCovariance && !opt.apsKnown)
    {
        PhaseTimer covarianceTimer(ctx.log, "AP covariance");
        ceres::Covariance::Options co;
        co.algorithm_type = ceres::SPARSE_QR;
        co.num_threads = opt.threads;
        ceres::Covariance cov(co);
        std::vector<std::pair<const double*, const double*>> blocks;
        for (size_t j = 0; j < A.size(); ++j)
            if (apUsed[j]) blocks.emplace_back(A[j].data(), A[j].data());
        if (!blocks.empty() && cov.Compute(blocks, &problem))
        {
            for (size_t j = 0; j < A.size(); ++j)
            {
                if (!apUsed[j]) continue;
                double c[9];
                cov.GetCovarianceBlock(A[j].data(), A[j].data(), c);
                res.apCov[j] = {c[0], c[1], c[4]};
            }
            res.apCovarianceOk = true;
        }
    }

    // ---- Results, also as an MRPT graph (poses, then AP vertices; odometry edges).
    for (size_t k = 0; k < N; ++k)
    {
        const TPose2D p(X[k][0], X[k][1], wrapToPi(X[k][2]));
        res.poses.push_back(nodes.t[k], p);
        res.graph.nodes[k] = mrpt::poses::CPose2D(p);
    }
    for (size_t j = 0; j < A.size(); ++j)
    {
        auto t = apList[j];
        t.pose = TPose2D(A[j][0], A[j][1], wrapToPi(A[j][2]));
        res.aps.add(t);
        res.graph.nodes[N + j] = mrpt::poses::CPose2D(t.pose);
    }
    if (in.graph)
    {
        std::map<size_t, size_t> idx;
        for (size_t k = 0; k < graphIds.size(); ++k) idx[graphIds[k]] = k;
        for (const auto& [ids, e] : in.graph->edges)
            res.graph.insertEdge(idx[ids.first], idx[ids.second], e);
    }
    for (size_t k = 0; !in.graph && k + 1 < N; ++k)
    {
        // Odometry edges as MRPT stores them: relative pose and information.
        const TPose2D z = inverseCompose(nodes.poses[k], nodes.poses[k + 1]);
        mrpt::poses::CPosePDFGaussianInf e;
        e.mean = mrpt::poses::CPose2D(z);
        const double d = std::hypot(z.x, z.y);
        const double sxy = std::max(opt.odoSigmaXY_min, opt.odoSigmaXY_perSqrtM * std::sqrt(d));
        const double sth = std::max(opt.odoSigmaYaw_min, opt.odoSigmaYaw_perSqrtM * std::sqrt(d));
        e.cov_inv.setZero();
        e.cov_inv(0, 0) = e.cov_inv(1, 1) = 1 / (sxy * sxy);
        e.cov_inv(2, 2) = 1 / (sth * sth);
        res.graph.insertEdge(k, k + 1, e);
    }
    res.graph.root = 0;
    res.totalTime_s = total.Tac();
    return res;
}

/** The first poses of `solved` followed by the odometry continued from its last pose: the
 *  initial poses of the next, longer window. */
Trajectory2D continueWithOdometry(const Trajectory2D& solved, const Trajectory2D& odo)
{
    Trajectory2D out = solved;
    TPose2D odoAtEnd;
    if (!odo.interpolate(solved.t.back(), odoAtEnd))
        throw std::logic_error("graph SLAM: solved window outside the odometry");
    const TPose2D& end = solved.poses.back();
    for (size_t i = 0; i < odo.size(); ++i)
        if (odo.t[i] > solved.t.back())
            out.push_back(odo.t[i], compose(end, inverseCompose(odoAtEnd, odo.poses[i])));
    return out;
}

/** The grown start: solve the first window, then append one window after another, each
 *  starting from the previous solution continued by the odometry (see growthWindow_s); the
 *  last stage is the whole problem. A stage frees only the poses of its newest
 *  kFreeWindows windows (the older ones stay as solved) and, for unknown APs, keeps of the
 *  older bearings one per AP and cell of growthThinning_m (on the solved poses), which hold the
 *  APs; it starts the APs from the previous stage's solution (re-triangulated when their
 *  bearings have doubled). So a stage costs what two windows and the area hold, and the stages
 *  together grow linearly with the drive. Known APs: the first window is solved from each of
 *  `placements` and the lowest cost goes on (`chosen`: its index). */
GraphSlamResult solveGrown(
    const GraphSlamInput& in, const GraphSlamOptions& opt, const std::vector<TPose2D>& placements,
    size_t& stages, size_t& chosen, PhaseLog& log)
{
    constexpr double kFreeWindows = 4;
    const Trajectory2D& odo = in.odometry;
    const double W = opt.growthWindow_s, t0 = odo.t.front(), tEnd = odo.t.back();
    const size_t windows = size_t(std::max(1.0, std::round((tEnd - t0) / W)));
    GraphSlamOptions stageOpt = opt;
    stageOpt.apCovariance = false;  // only the last stage's covariance is wanted
    Trajectory2D solved;
    TransmitterMap solvedAps;
    std::map<MacAddress, size_t> triangulatedWith;
    stages = 0;
    chosen = 0;
    TPose2D place = placements.empty() ? TPose2D(0, 0, 0) : placements.front();
    // The stage's input grows with T: odometry appended; bearings = the thinned history of the
    // held poses + every bearing of the free windows.
    GraphSlamInput window;
    window.aps = in.aps;
    std::vector<BearingRecord> history, recent;
    std::set<std::tuple<MacAddress, long, long>> historyCells;
    size_t nextOdo = 0, nextBearing = 0;
    std::vector<size_t> byTime(in.bearings.size());
    std::iota(byTime.begin(), byTime.end(), 0);
    std::stable_sort(
        byTime.begin(), byTime.end(),
        [&](size_t a, size_t b) { return in.bearings[a].t < in.bearings[b].t; });
    for (double T = t0 + W;; T += W)
    {
        const bool last = T >= tEnd - 0.5 * W;  // a short tail joins the last stage
        const Trajectory2D init =
            solved.empty() ? Trajectory2D() : continueWithOdometry(solved, odo);
        const Trajectory2D* start = solved.empty() ? nullptr : &init;
        ++stages;
        SolveContext ctx{
            log,
            last ? "grown start (last of " + std::to_string(stages) + " windows)" : std::string()};
        ctx.carriedAps = solvedAps.empty() ? nullptr : &solvedAps;
        ctx.triangulatedWith = &triangulatedWith;
        ctx.finalOfGrown = last;
        if (last) return solveOnce(in, opt, place, start, ctx);

        PhaseTimer inputTimer(log, "grown-stage input");
        ctx.freeFrom = T - kFreeWindows * W;
        for (; nextOdo < odo.size() && odo.t[nextOdo] <= T; ++nextOdo)
            window.odometry.push_back(odo.t[nextOdo], odo.poses[nextOdo]);
        for (; nextBearing < byTime.size() && in.bearings[byTime[nextBearing]].t <= T;
             ++nextBearing)
            recent.push_back(in.bearings[byTime[nextBearing]]);
        // Bearings whose poses are held from now on: known APs need none of them; unknown ones
        // keep one per AP and cell, placed on the solved poses.
        size_t moved = 0;
        for (; moved < recent.size() && recent[moved].t < ctx.freeFrom; ++moved)
        {
            const auto& b = recent[moved];
            TPose2D robot;
            if (opt.apsKnown || opt.growthThinning_m <= 0 ||
                !(solved.empty() ? odo : solved).interpolate(b.t, robot))
                continue;
            if (solved.empty()) robot = compose(place, robot);
            const auto s = compose(robot, b.sensorPose);
            const auto [cx, cy] = decorrelationCell(s.x, s.y, opt.growthThinning_m);
            if (historyCells.emplace(b.transmitter, cx, cy).second) history.push_back(b);
        }
        recent.erase(recent.begin(), recent.begin() + long(moved));
        window.bearings = history;
        window.bearings.insert(window.bearings.end(), recent.begin(), recent.end());
        inputTimer.stop();
        try
        {
            GraphSlamResult r;
            if (solved.empty() && placements.size() > 1)
            {
                // Known APs: the placement whose first window fits best goes on.
                bool have = false;
                for (size_t i = 0; i < placements.size(); ++i)
                {
                    try
                    {
                        auto c = solveOnce(window, stageOpt, placements[i], nullptr, ctx);
                        if (!have || c.finalCost < r.finalCost)
                            r = std::move(c), have = true, chosen = i, place = placements[i];
                    }
                    catch (const std::runtime_error&)
                    {
                        // Not placeable this way: the others compete.
                    }
                }
                if (!have) throw std::runtime_error("no placement solvable");
            }
            else
                r = solveOnce(window, stageOpt, place, start, ctx);
            solved = std::move(r.poses);
            solvedAps = std::move(r.aps);
        }
        catch (const std::runtime_error&)
        {
            // Nothing to solve yet in this window (no bearings, no AP placeable): go on with the
            // odometry as it is.
        }
        if (log.sinceLastLine() >= 5)
        {
            std::ostringstream line;
            line << "grown start: window " << stages << " of about " << windows << " ("
                 << int(T - t0) << " s of " << int(tEnd - t0) << " s), " << window.bearings.size()
                 << " bearings in the stage";
            log.say(line.str());
        }
    }
}

/** Unknown APs: the start from all rays on the odometry and the grown start; lowest cost wins. */
GraphSlamResult solveUnknownAps(
    const GraphSlamInput& in, const GraphSlamOptions& opt, PhaseLog& log)
{
    mrpt::system::CTicTac total;
    const bool canGrow = !in.graph && opt.growthWindow_s > 0 && in.odometry.size() >= 2 &&
                         in.odometry.t.back() - in.odometry.t.front() > 1.5 * opt.growthWindow_s;
    SolveContext odometryStart{log, "odometry start (APs triangulated)"};
    if (canGrow) odometryStart.maxIterations = std::max(1, opt.odometryStartIterations);
    GraphSlamResult best = solveOnce(in, opt, TPose2D(0, 0, 0), nullptr, odometryStart);
    best.placement = "APs triangulated on the odometry";
    best.hypotheses = 1;
    if (canGrow)
    {
        size_t stages = 0, chosen = 0;
        auto grown = solveGrown(in, opt, {}, stages, chosen, log);
        best.hypotheses = 2;
        if (grown.finalCost < best.finalCost)
        {
            best = std::move(grown);
            best.hypotheses = 2;
            best.placement = "grown window by window (" + std::to_string(stages) + " windows of " +
                             std::to_string(int(std::round(opt.growthWindow_s))) + " s)";
        }
    }
    best.totalTime_s = total.Tac();
    return best;
}

/** 2D rigid transform T minimising Σ|T·a_i − b_i|² (Umeyama, no scale). */
TPose2D alignPoints(const Eigen::Matrix2Xd& a, const Eigen::Matrix2Xd& b)
{
    const Eigen::Matrix3d T = Eigen::umeyama(a, b, false);
    return TPose2D(T(0, 2), T(1, 2), std::atan2(T(1, 0), T(0, 0)));
}
}  // namespace

GraphSlamResult solveBearingGraph(const GraphSlamInput& in, const GraphSlamOptions& opt)
{
    PhaseLog log(opt);
    if (!opt.apsKnown)
    {
        auto r = solveUnknownAps(in, opt, log);
        log.copyTo(r);
        return r;
    }
    if (in.aps.empty()) throw std::runtime_error("graph SLAM: known APs requested, none given");
    if (in.odometry.size() < 2) throw std::runtime_error("graph SLAM: the odometry has < 2 poses");

    // Several starts, each optimised; the lowest final cost (the same problem for all) wins:
    // (1) the best distinct placements of the odometry among the APs over the first seconds;
    // (2) when those can't be trusted, the estimated-AP solution (which needs no placement)
    //     moved onto the map by the rigid transform that best aligns its APs with the known ones.
    mrpt::system::CTicTac total;
    Trajectory2D placed = in.odometry;  // what is placed: odometry, or the .graph's node poses
    if (in.graph && in.graph->nodes.size() == in.odometry.size())
    {
        placed = Trajectory2D();
        size_t k = 0;
        for (const auto& [id, p] : in.graph->nodes)
            placed.push_back(in.odometry.t[k++], p.asTPose());
    }
    GraphSlamResult best;
    bool have = false;
    size_t tried = 0;
    auto consider = [&](GraphSlamResult&& r, const std::string& how)
    {
        ++tried;
        if (!have || r.finalCost < best.finalCost)
        {
            best = std::move(r), have = true;
            best.placement = how;
        }
    };
    auto finish = [&]()
    {
        best.hypotheses = tried;
        best.totalTime_s = total.Tac();
        log.copyTo(best);
        return best;
    };
    if (!in.placements.empty())
    {
        for (size_t i = 0; i < in.placements.size(); ++i)
        {
            const std::string how = "given placement " + std::to_string(i + 1);
            consider(solveOnce(in, opt, in.placements[i], nullptr, {log, how}), how);
        }
        return finish();
    }
    constexpr double placementWindow_s = 30;
    std::vector<TPose2D> places;
    {
        PhaseTimer timer(log, "placement search");
        places = placeTrajectoryCandidates(
            placed, in.bearings, in.aps, placementWindow_s,
            size_t(std::max(1, opt.placementHypotheses)));
        log.say(
            "placement search: " + std::to_string(places.size()) + " candidates over the first " +
            std::to_string(int(placementWindow_s)) + " s in " + secondsText(timer.stop()));
    }
    // A long drive placed as a whole drifts far from the map (0.4 deg/m turns a 1.4 km drive by
    // more than a turn): each placement's full solve would start far from the solution and cost
    // hundreds of iterations. The grown start instead solves window by window from the
    // placement that fits the first window best.
    const bool canGrow = !in.graph && opt.growthWindow_s > 0 &&
                         in.odometry.t.back() - in.odometry.t.front() > 1.5 * opt.growthWindow_s;
    if (canGrow)
    {
        size_t stages = 0, chosen = 0;
        auto r = solveGrown(in, opt, places, stages, chosen, log);
        consider(
            std::move(r), "placement " + std::to_string(chosen + 1) +
                              " of the first 30 s, grown window by window (" +
                              std::to_string(stages) + " windows of " +
                              std::to_string(int(std::round(opt.growthWindow_s))) + " s)");
    }
    else
        for (size_t i = 0; i < places.size(); ++i)
        {
            const std::string how = "placement " + std::to_string(i + 1) + " of the first 30 s";
            consider(solveOnce(in, opt, places[i], nullptr, {log, how}), how);
        }
    if (!opt.alignEstimatedAps) return finish();

    // Is the placement clear? Bearings of fewer than 3 APs at the start leave it ambiguous (one
    // AP fixes no heading, two leave a mirror), and a solution that leaves many bearings
    // unexplained or did not converge started in a wrong mode.
    std::set<MacAddress> heardAtStart;
    for (const auto& b : in.bearings)
        if (b.t <= placed.t.front() + placementWindow_s && in.aps.find(b.transmitter))
            heardAtStart.insert(b.transmitter);
    std::string doubt;
    if (heardAtStart.size() < 3)
        doubt = "the first 30 s hear " + std::to_string(heardAtStart.size()) + " of the APs";
    else if (best.bearingsWithin3Sigma < opt.placementInlierShare)
        doubt = "the best placement explains only " +
                std::to_string(int(std::round(100 * best.bearingsWithin3Sigma))) +
                " % of the bearings";
    else if (!best.converged)
        doubt = "the best placement did not converge";
    if (doubt.empty()) return finish();

    log.say("placement unclear (" + doubt + "): also starting from the estimated-AP solution");
    GraphSlamOptions eo = opt;
    eo.apsKnown = false;
    std::optional<GraphSlamResult> est;
    try
    {
        est = solveUnknownAps(in, eo, log);  // names and arrays of in.aps only are used
    }
    catch (const std::runtime_error&)
    {
        // Not enough for the estimated-AP solution: the placements above stand.
    }
    if (est)
    {
        std::vector<std::pair<TPose2D, TPose2D>> pairs;
        for (const auto& t : est->aps.transmitters())
            if (const auto* k = in.aps.find(t.mac)) pairs.emplace_back(t.pose, k->pose);
        if (pairs.size() >= 2)
        {
            Eigen::Matrix2Xd a(2, pairs.size()), b(2, pairs.size());
            for (size_t i = 0; i < pairs.size(); ++i)
            {
                a.col(long(i)) << pairs[i].first.x, pairs[i].first.y;
                b.col(long(i)) << pairs[i].second.x, pairs[i].second.y;
            }
            const TPose2D T = alignPoints(a, b);
            Trajectory2D init;
            for (size_t k = 0; k < est->poses.size(); ++k)
                init.push_back(est->poses.t[k], compose(T, est->poses.poses[k]));
            // The estimated-AP solve fixes node 0 at the odometry's first pose: T also places
            // the odometry.
            const std::string how = "estimated-AP solution aligned to the map (" +
                                    std::to_string(pairs.size()) + " APs)";
            consider(solveOnce(in, opt, T, &init, {log, how}), how);
        }
    }
    return finish();
}

}  // namespace mrpt_wifi::localization
