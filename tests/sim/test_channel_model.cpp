/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * Ray paths of the simulator against hand-computed geometry: mirror images, reflection points,
 * unfolded lengths, angles, gains, blocking and pruning. */
#include <gtest/gtest.h>
#include <mrpt_wifi/sim/ChannelModel.h>

#include <cmath>

using namespace mrpt_wifi::sim;
using mrpt::math::TPoint2D;

namespace
{
constexpr double kLambda = 0.05;  // metres; any value, the geometry doesn't depend on it
const double kDeg = M_PI / 180.0;

Wall makeWall(TPoint2D a, TPoint2D b, std::complex<double> refl = {-0.5, 0})
{
    Wall w;
    w.from = a;
    w.to = b;
    w.reflection = refl;
    return w;
}

PropagationSpec order(unsigned n, double minGain_dB = -200)
{
    PropagationSpec s;
    s.maxReflectionOrder = n;
    s.minPathGain_dB = minGain_dB;
    return s;
}

const PropagationPath* findPath(
    const std::vector<PropagationPath>& paths, PathKind kind, int obj0, int obj1 = -1)
{
    for (const auto& p : paths)
        if (p.kind == kind && p.objectIndex[0] == obj0 && p.objectIndex[1] == obj1) return &p;
    return nullptr;
}

double dist(const TPoint2D& a, const TPoint2D& b)
{
    return std::hypot(a.x - b.x, a.y - b.y);
}
}  // namespace

TEST(ChannelModel, MirrorAcrossWallLines)
{
    const auto vertical = makeWall({0, -5}, {0, 5});
    EXPECT_NEAR(mirrorAcross(vertical, {1, 2}).x, -1, 1e-12);
    EXPECT_NEAR(mirrorAcross(vertical, {1, 2}).y, 2, 1e-12);
    // The line y = x maps (3, 1) to (1, 3); the segment's extent doesn't matter.
    const auto diagonal = makeWall({0, 0}, {1, 1});
    EXPECT_NEAR(mirrorAcross(diagonal, {3, 1}).x, 1, 1e-12);
    EXPECT_NEAR(mirrorAcross(diagonal, {3, 1}).y, 3, 1e-12);
}

TEST(ChannelModel, LineOfSightOnly)
{
    ChannelModel model({}, {}, {}, order(2));
    const auto paths = model.computePaths({1, 1}, {4, 5}, kLambda);
    ASSERT_EQ(paths.size(), 1u);
    const auto& los = paths[0];
    EXPECT_EQ(los.kind, PathKind::LineOfSight);
    EXPECT_NEAR(los.length_m, 5.0, 1e-12);
    EXPECT_NEAR(los.delay_s, 5.0 / kSpeedOfLight, 1e-20);
    EXPECT_NEAR(los.departure_rad, std::atan2(4, 3), 1e-12);
    EXPECT_NEAR(los.arrival_rad, std::atan2(-4, -3), 1e-12);             // towards the transmitter
    EXPECT_NEAR(std::abs(los.gain), kLambda / (4 * M_PI * 5.0), 1e-15);  // Friis amplitude
}

// One wall along y = 0, transmitter (0, 1), receiver (4, 3): the image is (0, −1), the ray
// meets the wall at (1, 0), the unfolded length is 4√2.
TEST(ChannelModel, FirstOrderReflectionHandComputed)
{
    const std::complex<double> gamma = std::polar(0.6, 2.0);
    ChannelModel model({makeWall({-10, 0}, {10, 0}, gamma)}, {}, {}, order(1));
    const auto paths = model.computePaths({0, 1}, {4, 3}, kLambda);
    ASSERT_EQ(paths.size(), 2u);
    const auto* r = findPath(paths, PathKind::Reflection, 0);
    ASSERT_NE(r, nullptr);
    EXPECT_EQ(r->interactionCount, 1);
    EXPECT_NEAR(r->interactions[0].x, 1.0, 1e-12);
    EXPECT_NEAR(r->interactions[0].y, 0.0, 1e-12);
    EXPECT_NEAR(r->length_m, 4 * std::sqrt(2.0), 1e-12);
    EXPECT_NEAR(r->departure_rad, -45 * kDeg, 1e-12);
    EXPECT_NEAR(r->arrival_rad, -135 * kDeg, 1e-12);
    const std::complex<double> expected = gamma * kLambda / (4 * M_PI * 4 * std::sqrt(2.0));
    EXPECT_NEAR(std::abs(r->gain - expected), 0.0, 1e-15);
}

// Two walls meeting at the origin: A along +x, B along +y. Transmitter (1, 1), receiver (3, 2).
// First order: A at (5/3, 0), length √13; B at (0, 5/4), length √17.
// Second order via B then A: image (−1, −1), points (0, 1/4) then (1/3, 0), length 5 (legs
// 1.25 + 5/12 + 10/3). The order A then B would need a point outside B: it must not exist.
TEST(ChannelModel, SecondOrderCornerHandComputed)
{
    const std::complex<double> ga{-0.5, 0.1}, gb{0.3, -0.4};
    ChannelModel model(
        {makeWall({0, 0}, {10, 0}, ga), makeWall({0, 0}, {0, 10}, gb)}, {}, {}, order(2));
    const auto paths = model.computePaths({1, 1}, {3, 2}, kLambda);

    const auto* a = findPath(paths, PathKind::Reflection, 0);
    ASSERT_NE(a, nullptr);
    EXPECT_NEAR(a->interactions[0].x, 5.0 / 3, 1e-12);
    EXPECT_NEAR(a->interactions[0].y, 0.0, 1e-12);
    EXPECT_NEAR(a->length_m, std::sqrt(13.0), 1e-12);

    const auto* b = findPath(paths, PathKind::Reflection, 1);
    ASSERT_NE(b, nullptr);
    EXPECT_NEAR(b->interactions[0].x, 0.0, 1e-12);
    EXPECT_NEAR(b->interactions[0].y, 1.25, 1e-12);
    EXPECT_NEAR(b->length_m, std::sqrt(17.0), 1e-12);

    const auto* ba = findPath(paths, PathKind::Reflection, 1, 0);
    ASSERT_NE(ba, nullptr);
    EXPECT_EQ(ba->interactionCount, 2);
    EXPECT_NEAR(ba->interactions[0].x, 0.0, 1e-12);
    EXPECT_NEAR(ba->interactions[0].y, 0.25, 1e-12);
    EXPECT_NEAR(ba->interactions[1].x, 1.0 / 3, 1e-12);
    EXPECT_NEAR(ba->interactions[1].y, 0.0, 1e-12);
    EXPECT_NEAR(ba->length_m, 5.0, 1e-12);
    EXPECT_NEAR(1.25 + 5.0 / 12 + 10.0 / 3, 5.0, 1e-12);
    EXPECT_NEAR(ba->departure_rad, std::atan2(-0.75, -1.0), 1e-12);
    EXPECT_NEAR(ba->arrival_rad, std::atan2(-2.0, 1.0 / 3 - 3), 1e-12);
    const std::complex<double> expected = gb * ga * kLambda / (4 * M_PI * 5.0);
    EXPECT_NEAR(std::abs(ba->gain - expected), 0.0, 1e-15);

    EXPECT_EQ(findPath(paths, PathKind::Reflection, 0, 1), nullptr);
    EXPECT_EQ(paths.size(), 4u);  // LoS, A, B, B→A
}

TEST(ChannelModel, NoReflectionFromTheOtherSideOfAWall)
{
    ChannelModel model({makeWall({-10, 0}, {10, 0})}, {}, {}, order(2));
    // Receiver below the wall, transmitter above: the wall can't reflect between them (and the
    // line of sight crosses it).
    const auto paths = model.computePaths({0, 1}, {2, -1}, kLambda);
    ASSERT_EQ(paths.size(), 1u);
    EXPECT_NEAR(paths[0].crossingLoss_dB, Wall().transmissionLoss_dB, 1e-12);
}

TEST(ChannelModel, ReflectionPointMustLieOnTheSegment)
{
    // The same geometry as the first-order case, but the wall ends at x = 0.5 < 1.
    ChannelModel model({makeWall({-10, 0}, {0.5, 0})}, {}, {}, order(1));
    EXPECT_EQ(model.computePaths({0, 1}, {4, 3}, kLambda).size(), 1u);
}

// In a rectangular room every path must obey the law of reflection and have the unfolded length
// of its legs. For two inside points there are 4 first-order paths, 4 second-order ones between
// opposite walls and 4 corner paths (of the two orders of a corner only one can exist, see
// SecondOrderCornerHandComputed).
TEST(ChannelModel, RectangularRoomPathsAreGeometricallyConsistent)
{
    std::vector<Wall> walls;
    const std::vector<TPoint2D> c{{0, 0}, {10, 0}, {10, 5}, {0, 5}};
    for (size_t i = 0; i < 4; ++i) walls.push_back(makeWall(c[i], c[(i + 1) % 4]));
    ChannelModel model(walls, {}, {}, order(2));
    const TPoint2D tx{2.3, 3.9}, rx{7.1, 1.2};
    const auto paths = model.computePaths(tx, rx, kLambda);
    ASSERT_EQ(paths.size(), 1u + 4u + 4u + 4u);
    for (const auto& p : paths)
    {
        if (p.kind != PathKind::Reflection) continue;
        std::vector<TPoint2D> pts{tx};
        for (unsigned i = 0; i < p.interactionCount; ++i) pts.push_back(p.interactions[i]);
        pts.push_back(rx);
        double legs = 0;
        for (size_t i = 0; i + 1 < pts.size(); ++i) legs += dist(pts[i], pts[i + 1]);
        EXPECT_NEAR(legs, p.length_m, 1e-9);
        for (unsigned i = 0; i < p.interactionCount; ++i)
        {
            // Law of reflection: the previous point mirrored across the wall lies on the line
            // from the reflection point to the next point.
            const Wall& w = walls[size_t(p.objectIndex[i])];
            const TPoint2D prev = pts[i], here = pts[i + 1], next = pts[i + 2];
            const TPoint2D m = mirrorAcross(w, prev);
            const double crossZ =
                (m.x - here.x) * (next.y - here.y) - (m.y - here.y) * (next.x - here.x);
            EXPECT_NEAR(crossZ, 0.0, 1e-9);
            const double dot =
                (m.x - here.x) * (next.x - here.x) + (m.y - here.y) * (next.y - here.y);
            EXPECT_LT(dot, 0.0);  // on opposite sides of the reflection point
        }
        EXPECT_NEAR(p.departure_rad, std::atan2(pts[1].y - tx.y, pts[1].x - tx.x), 1e-12);
        EXPECT_NEAR(
            p.arrival_rad, std::atan2(pts[pts.size() - 2].y - rx.y, pts[pts.size() - 2].x - rx.x),
            1e-12);
    }
}

TEST(ChannelModel, ObstacleAttenuatesLineOfSightOnly)
{
    Obstacle o;
    o.from = {2, -1};
    o.to = {2, 1};
    o.attenuation_dB = 9;
    ChannelModel model({}, {o}, {}, order(2));
    const auto blocked = model.computePaths({0, 0}, {4, 0}, kLambda);
    ASSERT_EQ(blocked.size(), 1u);
    EXPECT_NEAR(blocked[0].crossingLoss_dB, 9.0, 1e-12);
    EXPECT_NEAR(
        std::abs(blocked[0].gain), kLambda / (4 * M_PI * 4) * std::pow(10, -9.0 / 20), 1e-15);
    const auto clear = model.computePaths({0, 0}, {0, 4}, kLambda);
    EXPECT_NEAR(clear[0].crossingLoss_dB, 0.0, 1e-12);
}

TEST(ChannelModel, ScattererBistaticPath)
{
    Scatterer s;
    s.position = {3, 4};
    s.radarCrossSection_m2 = 2.0;
    s.phase_rad = 0.7;
    ChannelModel model({}, {}, {s}, order(0));
    const auto paths = model.computePaths({0, 0}, {6, 0}, kLambda);
    const auto* p = findPath(paths, PathKind::Scattering, 0);
    ASSERT_NE(p, nullptr);
    EXPECT_NEAR(p->length_m, 10.0, 1e-12);  // 5 + 5
    EXPECT_NEAR(p->departure_rad, std::atan2(4, 3), 1e-12);
    EXPECT_NEAR(p->arrival_rad, std::atan2(4, -3), 1e-12);
    const double amp = std::sqrt(2.0) * kLambda / (std::pow(4 * M_PI, 1.5) * 5 * 5);
    EXPECT_NEAR(std::abs(p->gain), amp, 1e-15);
    EXPECT_NEAR(std::arg(p->gain), 0.7, 1e-12);
}

TEST(ChannelModel, WeakPathsArePrunedButNeverTheLineOfSight)
{
    // A heavily blocked line of sight and a strong reflection: with a −10 dB threshold the
    // line of sight survives (always) and the reflection stays; a weak second wall goes.
    Obstacle o;
    o.from = {2, -1};
    o.to = {2, 1};
    o.attenuation_dB = 60;
    ChannelModel model(
        {makeWall({-10, 3}, {10, 3}, {-0.9, 0}), makeWall({-10, -3}, {10, -3}, {0.001, 0})}, {o},
        {}, order(1, -10));
    const auto paths = model.computePaths({0, 0}, {4, 0}, kLambda);
    ASSERT_EQ(paths.size(), 2u);
    EXPECT_EQ(paths[0].kind, PathKind::LineOfSight);
    EXPECT_NE(findPath(paths, PathKind::Reflection, 0), nullptr);
}
