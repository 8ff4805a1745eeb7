/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/math/wrap2pi.h>
#include <mrpt_wifi/sim/Trajectory.h>

#include <algorithm>
#include <cmath>

namespace mrpt_wifi::sim
{
using mrpt::math::TPoint2D;
using mrpt::math::TPose2D;
using mrpt::math::TTwist2D;
using mrpt::math::wrapToPi;

namespace
{
constexpr double kWallClearance_m = 0.3;  // random drives keep this far from walls, scatterers
constexpr double kHeadingGain = 3.0;      // ω = k·heading error, clamped to the turn-rate limit

double distanceToSegment(const TPoint2D& p, const TPoint2D& a, const TPoint2D& b)
{
    const TPoint2D d = b - a;
    const double len2 = d.x * d.x + d.y * d.y;
    double t = len2 > 0 ? ((p.x - a.x) * d.x + (p.y - a.y) * d.y) / len2 : 0.0;
    t = std::clamp(t, 0.0, 1.0);
    return std::hypot(p.x - (a.x + t * d.x), p.y - (a.y + t * d.y));
}

bool segmentsCross(const TPoint2D& p, const TPoint2D& q, const TPoint2D& a, const TPoint2D& b)
{
    auto side = [](const TPoint2D& o, const TPoint2D& u, const TPoint2D& v)
    { return (u.x - o.x) * (v.y - o.y) - (u.y - o.y) * (v.x - o.x); };
    const double d1 = side(a, b, p), d2 = side(a, b, q), d3 = side(p, q, a), d4 = side(p, q, b);
    return ((d1 > 0) != (d2 > 0)) && ((d3 > 0) != (d4 > 0));
}

/** A random goal in the disc that the robot can reach in a straight line. */
TPoint2D drawGoal(const Scenario& sc, const TPoint2D& from, mrpt::random::CRandomGenerator& rng)
{
    const auto& m = sc.motion;
    for (int attempt = 0; attempt < 200; ++attempt)
    {
        const double r = m.randomWalkRadius_m * std::sqrt(rng.drawUniform(0.0, 1.0));
        const double a = rng.drawUniform(-M_PI, M_PI);
        const TPoint2D g{
            m.randomWalkCenter.x + r * std::cos(a), m.randomWalkCenter.y + r * std::sin(a)};
        if (!sc.insideRoom(g)) continue;
        bool ok = true;
        for (const auto& w : sc.walls)
            ok = ok && distanceToSegment(g, w.from, w.to) > kWallClearance_m &&
                 !segmentsCross(from, g, w.from, w.to);
        for (const auto& o : sc.obstacles)
            ok = ok && distanceToSegment(g, o.from, o.to) > kWallClearance_m &&
                 !segmentsCross(from, g, o.from, o.to);
        for (const auto& sct : sc.scatterers)  // pillars: don't drive through them
            ok = ok && distanceToSegment(sct.position, from, g) > kWallClearance_m;
        if (ok) return g;
    }
    return m.randomWalkCenter;  // cramped scene: go back to the centre
}
}  // namespace

Trajectory Trajectory::generate(const Scenario& sc, mrpt::random::CRandomGenerator& rng)
{
    const MotionSpec& m = sc.motion;
    Trajectory tr;
    tr.dt_ = m.timeStep_s;
    tr.duration_ = sc.duration_s;
    const size_t n = size_t(std::ceil(sc.duration_s / tr.dt_)) + 2;
    tr.poses_.reserve(n);
    tr.twists_.reserve(n);

    TPose2D pose = m.start;
    size_t waypoint = 0;
    bool moving = m.type != MotionType::Static;
    TPoint2D goal{pose.x, pose.y};
    if (m.type == MotionType::RandomWalk)
        goal = drawGoal(sc, {pose.x, pose.y}, rng);
    else if (moving)
        goal = m.waypoints.front();

    size_t pausedUntil = 0;  // step index the robot stays stopped until (dwell at goals)
    for (size_t i = 0; i < n; ++i)
    {
        TTwist2D tw{0, 0, 0};
        if (moving && i >= pausedUntil)
        {
            double dist = std::hypot(goal.x - pose.x, goal.y - pose.y);
            if (dist < m.goalTolerance_m)
            {
                ++tr.goalsReached_;
                if (m.dwellMax_s > 0)
                    pausedUntil = i + size_t(rng.drawUniform(0.0, m.dwellMax_s) / tr.dt_);
                if (m.type == MotionType::RandomWalk)
                    goal = drawGoal(sc, {pose.x, pose.y}, rng);
                else if (m.type == MotionType::Loop)
                    goal = m.waypoints[++waypoint % m.waypoints.size()];
                else if (++waypoint < m.waypoints.size())
                    goal = m.waypoints[waypoint];
                else
                    moving = false;
                dist = std::hypot(goal.x - pose.x, goal.y - pose.y);
            }
            if (moving && i >= pausedUntil)
            {
                const double err =
                    wrapToPi(std::atan2(goal.y - pose.y, goal.x - pose.x) - pose.phi);
                tw.omega = std::clamp(kHeadingGain * err, -m.turnRate_radps, m.turnRate_radps);
                // Turn on the spot when facing away; slow down on the final approach.
                tw.vx = std::min(m.speed_mps * std::max(0.0, std::cos(err)), 2.0 * dist);
            }
        }
        tr.poses_.push_back(pose);
        tr.twists_.push_back(tw);
        // Exact-enough unicycle step (midpoint heading).
        const double midHeading = pose.phi + 0.5 * tw.omega * tr.dt_;
        pose.x += tw.vx * tr.dt_ * std::cos(midHeading);
        pose.y += tw.vx * tr.dt_ * std::sin(midHeading);
        pose.phi = wrapToPi(pose.phi + tw.omega * tr.dt_);
        tr.pathLength_ += tw.vx * tr.dt_;
    }
    return tr;
}

TPose2D Trajectory::poseAt(double t_s) const
{
    const double u = std::clamp(t_s, 0.0, duration_) / dt_;
    const size_t i = std::min(size_t(u), poses_.size() - 2);
    const double f = u - double(i);
    const TPose2D& a = poses_[i];
    const TPose2D& b = poses_[i + 1];
    return {
        a.x + f * (b.x - a.x), a.y + f * (b.y - a.y),
        wrapToPi(a.phi + f * wrapToPi(b.phi - a.phi))};
}

TTwist2D Trajectory::velocityAt(double t_s) const
{
    const double u = std::clamp(t_s, 0.0, duration_) / dt_;
    return twists_[std::min(size_t(u), twists_.size() - 1)];
}

std::vector<OdometrySample> simulateOdometry(
    const Trajectory& traj, const OdometrySpec& spec, mrpt::random::CRandomGenerator& rng)
{
    std::vector<OdometrySample> out;
    if (!spec.enabled) return out;
    const double period = 1.0 / spec.rate_Hz;
    const size_t n = size_t(std::floor(traj.duration() * spec.rate_Hz + 1e-9)) + 1;
    out.reserve(n);

    OdometrySample s;
    s.time_s = 0;
    s.truth = traj.poseAt(0);
    s.odometry = spec.startAtOrigin ? TPose2D(0, 0, 0) : s.truth;
    out.push_back(s);
    for (size_t j = 1; j < n; ++j)
    {
        OdometrySample next;
        next.time_s = double(j) * period;
        next.truth = traj.poseAt(next.time_s);
        const TPose2D delta = next.truth - s.truth;  // in the previous robot frame
        const double d = std::hypot(delta.x, delta.y);
        const double sxy = spec.sigmaXY_m_per_sqrt_m * std::sqrt(d);
        const double syaw = std::sqrt(
            spec.sigmaYaw_rad_per_sqrt_m * spec.sigmaYaw_rad_per_sqrt_m * d +
            spec.sigmaYaw_rad_per_sqrt_rad * spec.sigmaYaw_rad_per_sqrt_rad * std::abs(delta.phi));
        TPose2D measured;
        measured.x = delta.x * (1 + spec.scaleError) + rng.drawGaussian1D(0, sxy);
        measured.y = delta.y * (1 + spec.scaleError) + rng.drawGaussian1D(0, sxy);
        measured.phi = delta.phi * (1 + spec.yawScaleError) + spec.yawDrift_rad_per_m * d +
                       rng.drawGaussian1D(0, syaw);
        next.odometry = s.odometry + measured;
        next.velocityLocal = {measured.x / period, measured.y / period, measured.phi / period};
        out.push_back(next);
        s = next;
    }
    return out;
}

}  // namespace mrpt_wifi::sim
