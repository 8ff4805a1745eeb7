/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

// A small geometric world for the localization tests: APs at known poses, a robot driving a
// loop, odometry with bias and noise, and bearings (AoA/AoD) with Gaussian noise, outliers and
// the mirror ambiguity of linear arrays. Independent of the radio simulator on purpose: the
// tests check the estimators against exactly known geometry.

#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>

#include <array>
#include <cmath>
#include <vector>

namespace mrpt_wifi::loctest
{
using namespace mrpt_wifi::localization;

struct WorldOptions
{
    double duration_s = 120;
    double speed = 0.5;
    double rate_Hz = 5;  //!< bearings per AP per second
    double aoaStd = 0.05, aodStd = 0.07;
    double outliers = 0.03;
    double odoScaleError = 0.02;  //!< odometry drift
    double odoYawDrift = 0.006;   //!< rad per metre
    bool aod = true;
    /** Multipath: an AoA error that depends on where the robot is, the same on every lap (per
     *  AP a smooth field of this amplitude [rad], wavelength multipathScale_m). */
    double multipathAmplitude = 0;
    double multipathScale_m = 1.5;
    uint64_t seed = 3;
    /** > 0: at each corner the robot stands and turns on the spot at this rate [rad/s]
     *  (0: it turns at once), and its bearings meanwhile have σ turningAoaStd (a real array's
     *  bearings smear while the robot turns). */
    double cornerTurnRate = 0;
    double turningAoaStd = 1.0;
    std::vector<mrpt::math::TPoint2D> loop = {{2, 2}, {8, 2}, {8, 4}, {2, 4}};
};

inline TransmitterMap makeAps(const std::vector<mrpt::math::TPose2D>& poses)
{
    TransmitterMap m;
    for (size_t i = 0; i < poses.size(); ++i)
    {
        KnownTransmitter t;
        t.mac = MacAddress::fromString("02:00:00:00:0a:0" + std::to_string(i + 1));
        t.name = "ap" + std::to_string(i + 1);
        t.pose = poses[i];
        t.array = ArrayGeometry::fromElements({{0, -0.039}, {0, -0.013}, {0, 0.013}, {0, 0.039}});
        m.add(t);
    }
    return m;
}

struct World
{
    TransmitterMap aps;
    Trajectory2D truth, odometry;
    std::vector<BearingRecord> bearings;
    ArrayGeometry rxArray = ArrayGeometry::fromElements({{0, 0}, {0, 0.052}});
};

/** Drives the loop at constant speed (100 Hz truth, 20 Hz odometry) and measures bearings. */
inline World makeWorld(const TransmitterMap& aps, const WorldOptions& o)
{
    World w;
    w.aps = aps;
    mrpt::random::CRandomGenerator rng(o.seed);
    // Truth: piecewise straight drive along the loop, heading along the segment.
    const double dt = 0.01;
    size_t seg = 0;
    mrpt::math::TPose2D p(o.loop[0].x, o.loop[0].y, 0);
    std::vector<bool> turning;  // per truth sample
    const double t0 = 1700000000.0;
    for (double t = 0; t <= o.duration_s; t += dt)
    {
        const auto& goal = o.loop[(seg + 1) % o.loop.size()];
        const double dx = goal.x - p.x, dy = goal.y - p.y, d = std::hypot(dx, dy);
        const double turn = wrapToPi(std::atan2(dy, dx) - p.phi);
        bool turningNow = false;
        if (d < o.speed * dt)
            ++seg;
        else if (o.cornerTurnRate > 0 && t > 0 && std::abs(turn) > o.cornerTurnRate * dt)
        {
            p.phi = wrapToPi(p.phi + std::copysign(o.cornerTurnRate * dt, turn));
            turningNow = true;
        }
        else
        {
            p.phi = std::atan2(dy, dx);
            p.x += o.speed * dt * dx / d;
            p.y += o.speed * dt * dy / d;
        }
        w.truth.push_back(t0 + t, p);
        turning.push_back(turningNow);
    }
    // Odometry: integrate noisy, biased increments every 0.05 s.
    mrpt::math::TPose2D odo(0, 0, 0);
    w.odometry.push_back(w.truth.t[0], odo);
    for (size_t i = 5; i < w.truth.size(); i += 5)
    {
        const auto& a = w.truth.poses[i - 5];
        const auto& b = w.truth.poses[i];
        const double c = std::cos(a.phi), s = std::sin(a.phi);
        double fx = c * (b.x - a.x) + s * (b.y - a.y);
        double fy = -s * (b.x - a.x) + c * (b.y - a.y);
        double dth = wrapToPi(b.phi - a.phi);
        const double dist = std::hypot(fx, fy);
        fx = fx * (1 + o.odoScaleError) + 0.005 * std::sqrt(dist) * rng.drawGaussian1D_normalized();
        fy = fy * (1 + o.odoScaleError);
        dth += o.odoYawDrift * dist + 0.005 * std::sqrt(dist) * rng.drawGaussian1D_normalized();
        const double co = std::cos(odo.phi), so = std::sin(odo.phi);
        odo = mrpt::math::TPose2D(
            odo.x + co * fx - so * fy, odo.y + so * fx + co * fy, wrapToPi(odo.phi + dth));
        w.odometry.push_back(w.truth.t[i], odo);
    }
    // Multipath field per AP: random phases and directions, drawn once (own generator: the
    // other draws stay as they were without multipath).
    mrpt::random::CRandomGenerator fieldRng(o.seed + 7919);
    struct Wave
    {
        double kx, ky, phase;
    };
    std::vector<std::array<Wave, 2>> fields(aps.size());
    for (auto& f : fields)
        for (auto& wv : f)
        {
            const double dir = fieldRng.drawUniform(-M_PI, M_PI), k = 2 * M_PI / o.multipathScale_m;
            wv = {k * std::cos(dir), k * std::sin(dir), fieldRng.drawUniform(-M_PI, M_PI)};
        }
    const auto multipath = [&](size_t ap, double x, double y)
    {
        double e = 0;
        for (const auto& wv : fields[ap]) e += std::sin(wv.kx * x + wv.ky * y + wv.phase);
        return o.multipathAmplitude * e / std::sqrt(2.0);
    };
    // Bearings.
    const mrpt::math::TPose2D sensor(0.1, 0, 0);
    const size_t step = size_t(std::round(1.0 / (o.rate_Hz * dt)));
    for (size_t i = 0; i < w.truth.size() && w.truth.t[i] < w.odometry.t.back(); i += step)
        for (size_t j = 0; j < aps.size(); ++j)
        {
            const auto& ap = aps.transmitters()[j];
            BearingRecord r;
            r.t = w.truth.t[i] + 1e-4;
            r.transmitter = ap.mac;
            r.sensorPose = sensor;
            const auto s = sensorWorldPose(w.truth.poses[i], sensor);
            auto noisy = [&](double v, double sd)
            {
                return rng.drawUniform(0.0, 1.0) < o.outliers
                           ? rng.drawUniform(-M_PI, M_PI)
                           : wrapToPi(v + sd * rng.drawGaussian1D_normalized());
            };
            auto report = [&](const ArrayGeometry& g, double v, double& out, bool& amb, double& m)
            {
                amb = true;
                const double mv = g.mirrorOf(v);
                if (g.inFrontHalf(v))
                    out = v, m = mv;
                else
                    out = mv, m = v;
            };
            r.hasAoa = true;
            r.aoaStd = turning[i] ? o.turningAoaStd : o.aoaStd;
            report(
                w.rxArray,
                noisy(predictAoa(s, ap.pose.x, ap.pose.y) + multipath(j, s.x, s.y), r.aoaStd),
                r.aoa, r.aoaAmbiguous, r.aoaMirror);
            if (o.aod)
            {
                r.hasAod = true;
                r.aodStd = o.aodStd;
                report(
                    ap.array, noisy(predictAod(ap.pose, s.x, s.y), o.aodStd), r.aod, r.aodAmbiguous,
                    r.aodMirror);
            }
            w.bearings.push_back(r);
        }
    return w;
}

}  // namespace mrpt_wifi::loctest
