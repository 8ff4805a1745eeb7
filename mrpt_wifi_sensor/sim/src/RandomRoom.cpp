/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/sim/RandomRoom.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "CounterRng.h"

namespace mrpt_wifi::sim
{
namespace
{
/** Salt of the room generator's stream, apart from the simulator's own tags. */
constexpr uint64_t kTagRandomRoom = 0x524f4f4dULL;         // "ROOM"
constexpr uint64_t kTagExtraAccessPoints = 0x4150584eULL;  // "APXN"

struct Point
{
    double x, y;
};

double pointToSegment(const Point& p, const Point& a, const Point& b)
{
    const double dx = b.x - a.x, dy = b.y - a.y, len2 = dx * dx + dy * dy;
    const double u =
        len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
    return std::hypot(p.x - a.x - u * dx, p.y - a.y - u * dy);
}

/** Distance between two segments (0 when they cross). */
double segmentDistance(const Point& a, const Point& b, const Point& c, const Point& d)
{
    const auto side = [](const Point& o, const Point& p, const Point& q)
    { return (p.x - o.x) * (q.y - o.y) - (p.y - o.y) * (q.x - o.x); };
    if (side(a, b, c) * side(a, b, d) < 0 && side(c, d, a) * side(c, d, b) < 0) return 0;
    return std::min(
        {pointToSegment(a, c, d), pointToSegment(b, c, d), pointToSegment(c, a, b),
         pointToSegment(d, a, b)});
}

std::string pt(const Point& p)
{
    std::ostringstream o;
    o << std::fixed << std::setprecision(3) << "[" << p.x << ", " << p.y << "]";
    return o.str();
}
}  // namespace

bool isRandomRoomReceiver(const std::string& name)
{
    return name == "rt-ac86u" || name == "intel5300";
}

std::string randomRoomYaml(uint32_t seed, const RandomRoomOptions& options)
{
    if (!isRandomRoomReceiver(options.receiver))
        throw std::invalid_argument(
            "unknown random-room receiver '" + options.receiver + "' (rt-ac86u or intel5300)");
    if (options.accessPoints < 3 || options.accessPoints > 250)
        throw std::invalid_argument(
            "random room: " + std::to_string(options.accessPoints) + " access points (3 to 250)");
    if (options.accessPointStreams != 0 && options.accessPointStreams != 2 &&
        options.accessPointStreams != 4)
        throw std::invalid_argument(
            "random room: " + std::to_string(options.accessPointStreams) +
            " streams per access point (0: drawn, 2 or 4)");
    const bool intel = options.receiver == "intel5300";
    // Uniform reals in [a, b) and integers in [a, b] drawn from a generator.
    const auto uniformFrom = [](mrpt::random::CRandomGenerator& g)
    { return [&g](double a, double b) { return g.drawUniform(a, b); }; };
    const auto integerFrom = [](mrpt::random::CRandomGenerator& g)
    { return [&g](int a, int b) { return int(std::floor(g.drawUniform(a, b + 1 - 1e-9))); }; };
    mrpt::random::CRandomGenerator rng(detail::seed32(detail::hashKey({seed, kTagRandomRoom})));
    const auto U = uniformFrom(rng);
    const auto I = integerFrom(rng);

    const double W = U(6, 14), H = U(5, 10);
    std::ostringstream y;  // everything after the header (the duration of a loop comes last)
    y << std::fixed << std::setprecision(3);
    double duration_s = options.duration_s;
    y << "room:\n  corners: [[0, 0], [" << W << ", 0], [" << W << ", " << H << "], [0, " << H
      << "]]\n";
    const double gamma = U(0.2, 0.5);
    y << "  reflection: {magnitude: " << gamma << ", phase_deg: " << U(160, 200) << "}\n\n";

    // Furniture: segments away from the walls; their edges scatter.
    std::vector<Point> edgePoints;
    y << "obstacles:\n";
    const int nFurniture = I(1, 2);
    for (int i = 0; i < nFurniture; ++i)
    {
        const double len = U(0.6, 1.5), a = U(-M_PI, M_PI);
        const Point c{U(1.2, W - 1.2), U(1.2, H - 1.2)};
        const Point p{c.x - 0.5 * len * std::cos(a), c.y - 0.5 * len * std::sin(a)};
        const Point q{c.x + 0.5 * len * std::cos(a), c.y + 0.5 * len * std::sin(a)};
        y << "  - {name: furniture" << i << ", from: " << pt(p) << ", to: " << pt(q)
          << ", attenuation_db: " << U(3, 10) << "}\n";
        edgePoints.push_back(p);
        edgePoints.push_back(q);
    }

    y << "\nscatterers:\n";
    int ns = 0;
    auto scatterer = [&](const Point& p, double rcs)
    {
        y << "  - {name: s" << ns++ << ", position: " << pt(p) << ", rcs_m2: " << rcs
          << ", phase_deg: " << U(-180, 180) << "}\n";
    };
    for (const auto& p : edgePoints) scatterer(p, U(0.02, 0.15));
    // Rough walls: weak scatterers 5–30 cm in front of each wall.
    for (int w = 0; w < 4; ++w)
        for (int k = I(2, 4); k > 0; --k)
        {
            const double d = U(0.05, 0.3);
            const Point p = w == 0   ? Point{U(0.3, W - 0.3), d}
                            : w == 1 ? Point{W - d, U(0.3, H - 0.3)}
                            : w == 2 ? Point{U(0.3, W - 0.3), H - d}
                                     : Point{d, U(0.3, H - 0.3)};
            scatterer(p, U(0.02, 0.15));
        }
    // Clusters (a shelf of metal objects, a machine, a desk with a monitor).
    for (int c = I(1, 3); c > 0; --c)
    {
        const Point centre{U(0.8, W - 0.8), U(0.8, H - 0.8)};
        for (int k = I(3, 5); k > 0; --k)
            scatterer({centre.x + U(-0.4, 0.4), centre.y + U(-0.4, 0.4)}, U(0.05, 0.5));
    }

    // Access points near the walls, facing into the room within ±60°.
    const auto accessPoint = [&](int t, auto&& uniform, auto&& integer)
    {
        const int wall = integer(0, 3);
        const double inset = uniform(0.2, 0.5);
        Point p;
        double inward = 0;
        if (wall == 0) p = {uniform(0.5, W - 0.5), inset}, inward = 90;
        if (wall == 1) p = {W - inset, uniform(0.5, H - 0.5)}, inward = 180;
        if (wall == 2) p = {uniform(0.5, W - 0.5), H - inset}, inward = -90;
        if (wall == 3) p = {inset, uniform(0.5, H - 0.5)}, inward = 0;
        const bool two = uniform(0, 1) < 0.5;  // drawn whatever the option: same stream
        const int streams = options.accessPointStreams > 0 ? options.accessPointStreams
                            : two                          ? 2
                                                           : 1;
        y << "  - name: ap" << t << "\n"
          << "    mac: '02:00:00:00:0a:" << std::hex << std::setw(2) << std::setfill('0') << (t + 1)
          << std::dec << std::setfill(' ') << "'\n"
          << "    position: " << pt(p) << "\n"
          << "    yaw_deg: " << inward + uniform(-60, 60) << "\n"
          << "    channel: " << (intel ? "159/40" : "155/80") << "\n"
          << "    streams: " << streams << "\n";
        if (streams > 1)
            y << "    array: " << options.arraysDir << "/ap-linear-" << streams << ".yaml\n";
        y << "    frame_rate_hz: 50\n";
    };
    y << "\ntransmitters:\n";
    for (int t = 0; t < 3; ++t) accessPoint(t, U, I);
    // Further APs come from their own stream: the room, its first three APs and the drive stay
    // those of the seed.
    mrpt::random::CRandomGenerator extraRng(
        detail::seed32(detail::hashKey({seed, kTagRandomRoom, kTagExtraAccessPoints})));
    for (int t = 3; t < options.accessPoints; ++t)
        accessPoint(t, uniformFrom(extraRng), integerFrom(extraRng));

    y << "\nreceiver:\n  label: WIFI_CSI\n  array: " << options.arraysDir
      << (intel ? "/intel5300-linear-3.yaml\n  csi_format: intel5300\n" : "/rt-ac86u.yaml\n")
      << "  sensor_pose: {x: 0.1, y: 0.0, z: 0.4, yaw_deg: 0}\n"
      << "  body_shadow: {center_deg: 180, width_deg: " << U(60, 140)
      << ", attenuation_db: " << U(3, 8) << "}\n\n";

    const Point start{U(1.0, W - 1.0), U(1.0, H - 1.0)};
    const double startYaw = U(-180, 180), speed = U(0.3, 0.7), turnRate = U(30, 90);
    if (options.loopLaps == 0)
        y << "motion:\n  type: random_walk\n  start: [" << start.x << ", " << start.y << ", "
          << startYaw << "]\n"
          << "  center: " << pt({0.5 * W, 0.5 * H}) << "\n"
          << "  radius_m: " << std::hypot(W, H) << "\n"
          << "  speed_mps: " << speed << "\n"
          << "  turn_rate_dps: " << turnRate << "\n"
          << "  dwell_s: 4\n\n";
    else
    {
        // The rectangle's distance to the furniture (0: it crosses a piece).
        const auto clearanceOf = [&](double left, double right, double bottom, double top)
        {
            const Point c[4] = {
                {left, bottom}, {W - right, bottom}, {W - right, H - top}, {left, H - top}};
            double clearance = 1e9;
            for (size_t f = 0; f + 1 < edgePoints.size(); f += 2)
                for (int k = 0; k < 4; ++k)
                    clearance = std::min(
                        clearance,
                        segmentDistance(c[k], c[(k + 1) % 4], edgePoints[f], edgePoints[f + 1]));
            return clearance;
        };
        // The inset whose rectangle keeps the most clearance from the furniture (the first
        // with 0.3 m, in order of preference).
        double inset = 1.0, bestClearance = -1;
        for (double d : {1.0, 0.8, 1.2, 1.5, 0.6, 1.8, 2.0})
        {
            const double clearance = clearanceOf(d, d, d, d);
            if (clearance > bestClearance) bestClearance = clearance, inset = d;
            if (clearance >= 0.3) break;
        }
        double left = inset, right = inset, bottom = inset, top = inset;
        if (bestClearance <= 0)
        {
            // Every concentric rectangle crosses a piece (2 of seeds 1–1999): an inset per
            // side, the longest loop with 0.3 m of clearance (else the clearest), at least
            // 1.5 m across. Only these rooms change: every room that could be driven before
            // stays the same.
            constexpr double kStep = 0.2, kMinInset = 0.6, kMinSide = 1.5, kClear = 0.3;
            double bestPerimeter = 0;
            for (double l = kMinInset; W - l - kMinInset >= kMinSide; l += kStep)
                for (double r = kMinInset; W - l - r >= kMinSide; r += kStep)
                    for (double b = kMinInset; H - b - kMinInset >= kMinSide; b += kStep)
                        for (double t = kMinInset; H - b - t >= kMinSide; t += kStep)
                        {
                            const double clearance = clearanceOf(l, r, b, t);
                            const double perimeter = 2 * (W - l - r + H - b - t);
                            const bool better =
                                bestClearance >= kClear
                                    ? clearance >= kClear && perimeter > bestPerimeter
                                    : clearance > bestClearance;
                            if (better)
                                bestClearance = clearance, bestPerimeter = perimeter, left = l,
                                right = r, bottom = b, top = t;
                        }
            if (bestClearance <= 0)
                throw std::runtime_error(
                    "random room " + std::to_string(seed) +
                    ": no loop keeps clear of the furniture");
        }
        // (left + right) + (bottom + top) is exactly 4 · inset for a concentric rectangle: the
        // lap, and so the duration, of every earlier room stays to the bit.
        const double lap =
            2 * (W + H - ((left + right) + (bottom + top))) / speed + 4 * 90 / turnRate;
        y << "motion:\n  type: loop\n  start: [" << left << ", " << bottom << ", 0]\n"
          << "  waypoints: [" << pt({W - right, bottom}) << ", " << pt({W - right, H - top}) << ", "
          << pt({left, H - top}) << ", " << pt({left, bottom}) << "]\n"
          << "  speed_mps: " << speed << "\n"
          << "  turn_rate_dps: " << turnRate << "\n\n";
        duration_s = options.loopLaps * lap;
    }
    y << "odometry:\n  rate_hz: 20\n";
    if (options.odometryScaleError != 0)
        y << "  scale_error: " << options.odometryScaleError << "\n";
    if (options.odometryYawScaleError != 0)
        y << "  yaw_scale_error: " << options.odometryYawScaleError << "\n";
    if (options.odometryYawDrift_deg_per_m != 0)
        y << "  yaw_drift_deg_per_m: " << options.odometryYawDrift_deg_per_m << "\n";
    y << "\n";
    y << "impairments:\n  ripple_deg: 4\n  sto_sigma_ns: 25\n";
    std::ostringstream head;
    head << std::fixed << std::setprecision(3);
    head << "# Random room " << seed << " ("
         << (isEvaluationSeed(seed) ? "evaluation" : "development") << " seed), generated by "
         << "mrpt_wifi::sim::randomRoomYaml\n";
    head << "name: random-room-" << seed << "\n";
    head << "description: random room " << W << " x " << H << " m"
         << (options.loopLaps ? ", " + std::to_string(options.loopLaps) + " laps of a loop" : "")
         << "\n";
    head << "duration_s: " << duration_s << "\n";
    head << "seed: " << seed << "\n\n";
    return head.str() + y.str();
}

Scenario randomRoomScenario(uint32_t seed, const RandomRoomOptions& options)
{
    return Scenario::fromYamlText(
        randomRoomYaml(seed, options), "random-room-" + std::to_string(seed), ".");
}

}  // namespace mrpt_wifi::sim
