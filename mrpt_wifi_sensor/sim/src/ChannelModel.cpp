/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/sim/ChannelModel.h>

#include <algorithm>
#include <cmath>

namespace mrpt_wifi::sim
{
using mrpt::math::TPoint2D;

const char* toString(PathKind k)
{
    switch (k)
    {
        case PathKind::LineOfSight:
            return "los";
        case PathKind::Reflection:
            return "reflection";
        case PathKind::Scattering:
            return "scattering";
    }
    return "unknown";
}

namespace
{
// Shortest distance used for spreading loss: avoids infinite gain when two points coincide.
constexpr double kMinDistance_m = 0.05;
// Intersections this close to a ray's ends belong to the walls it reflects on.
constexpr double kEndEpsilon = 1e-9;

double cross(const TPoint2D& a, const TPoint2D& b)
{
    return a.x * b.y - a.y * b.x;
}

/** Where segment p→q meets segment a→b: p + t(q−p) = a + s(b−a). False if parallel or
 *  outside (t in (eps, 1−eps), s in [0, 1]). */
bool segmentsMeet(
    const TPoint2D& p, const TPoint2D& q, const TPoint2D& a, const TPoint2D& b, double& t,
    double& s)
{
    const TPoint2D r = q - p, d = b - a;
    const double den = cross(r, d);
    if (std::abs(den) < 1e-15) return false;
    const TPoint2D ap = a - p;
    t = cross(ap, d) / den;
    s = cross(ap, r) / den;
    return t > kEndEpsilon && t < 1.0 - kEndEpsilon && s >= 0.0 && s <= 1.0;
}

double angleOf(const TPoint2D& from, const TPoint2D& to)
{
    return std::atan2(to.y - from.y, to.x - from.x);
}

double dB2amplitude(double dB)
{
    return std::pow(10.0, dB / 20.0);
}
}  // namespace

TPoint2D mirrorAcross(const Wall& w, const TPoint2D& p)
{
    const TPoint2D d = w.to - w.from;
    const double len2 = d.x * d.x + d.y * d.y;
    const TPoint2D v = p - w.from;
    const double along = (v.x * d.x + v.y * d.y) / len2;
    const TPoint2D foot{w.from.x + along * d.x, w.from.y + along * d.y};
    return {2 * foot.x - p.x, 2 * foot.y - p.y};
}

ChannelModel::ChannelModel(const Scenario& sc)
    : ChannelModel(sc.walls, sc.obstacles, sc.scatterers, sc.propagation)
{
}

ChannelModel::ChannelModel(
    std::vector<Wall> walls, std::vector<Obstacle> obstacles, std::vector<Scatterer> scatterers,
    PropagationSpec spec)
    : walls_(std::move(walls)),
      obstacles_(std::move(obstacles)),
      scatterers_(std::move(scatterers)),
      spec_(spec)
{
}

ChannelModel::ImageSet ChannelModel::imagesOf(const TPoint2D& transmitter) const
{
    ImageSet set;
    set.source = transmitter;
    if (spec_.maxReflectionOrder < 1) return set;
    const int nw = int(walls_.size());
    for (int w1 = 0; w1 < nw; ++w1)
    {
        ImageSet::Image first;
        first.position = mirrorAcross(walls_[w1], transmitter);
        first.walls = {{w1, -1}};
        first.order = 1;
        set.images.push_back(first);
        if (spec_.maxReflectionOrder < 2) continue;
        for (int w2 = 0; w2 < nw; ++w2)
        {
            if (w2 == w1) continue;  // the same wall twice in a row is not a reflection
            ImageSet::Image second;
            second.position = mirrorAcross(walls_[w2], first.position);
            second.walls = {{w1, w2}};
            second.order = 2;
            set.images.push_back(second);
        }
    }
    return set;
}

double ChannelModel::crossingLoss_dB(
    const TPoint2D& a, const TPoint2D& b, int skipWallA, int skipWallB) const
{
    double loss = 0, t = 0, s = 0;
    for (int w = 0; w < int(walls_.size()); ++w)
    {
        if (w == skipWallA || w == skipWallB) continue;
        if (segmentsMeet(a, b, walls_[w].from, walls_[w].to, t, s))
            loss += walls_[w].transmissionLoss_dB;
    }
    for (const auto& o : obstacles_)
        if (segmentsMeet(a, b, o.from, o.to, t, s)) loss += o.attenuation_dB;
    return loss;
}

void ChannelModel::computePaths(
    const ImageSet& tx, const TPoint2D& rx, double wavelength_m,
    std::vector<PropagationPath>& out) const
{
    out.clear();
    const TPoint2D& src = tx.source;
    const double friis = wavelength_m / (4.0 * M_PI);

    // Line of sight: always present (maybe attenuated), always first.
    {
        PropagationPath p;
        p.kind = PathKind::LineOfSight;
        p.length_m = std::hypot(rx.x - src.x, rx.y - src.y);
        p.departure_rad = angleOf(src, rx);
        p.arrival_rad = angleOf(rx, src);
        p.crossingLoss_dB = crossingLoss_dB(src, rx);
        p.gain = friis / std::max(p.length_m, kMinDistance_m) * dB2amplitude(-p.crossingLoss_dB);
        out.push_back(p);
    }

    // Specular reflections: trace back from the receiver through the image's wall sequence.
    for (const auto& img : tx.images)
    {
        double t = 0, s = 0;
        const int wLast = img.walls[img.order - 1];
        const Wall& last = walls_[wLast];
        if (!segmentsMeet(rx, img.position, last.from, last.to, t, s)) continue;
        const TPoint2D pLast{
            rx.x + t * (img.position.x - rx.x), rx.y + t * (img.position.y - rx.y)};

        PropagationPath p;
        p.kind = PathKind::Reflection;
        p.interactionCount = img.order;
        if (img.order == 1)
        {
            p.interactions[0] = pLast;
            p.objectIndex = {{wLast, -1}};
        }
        else
        {
            // The previous image is the mirror of this one across the last wall.
            const int wFirst = img.walls[0];
            const Wall& first = walls_[wFirst];
            const TPoint2D prevImage = mirrorAcross(last, img.position);
            if (!segmentsMeet(pLast, prevImage, first.from, first.to, t, s)) continue;
            p.interactions[0] = {
                pLast.x + t * (prevImage.x - pLast.x), pLast.y + t * (prevImage.y - pLast.y)};
            p.interactions[1] = pLast;
            p.objectIndex = {{wFirst, wLast}};
        }

        // Legs: source → i0 (→ i1) → receiver; each may cross walls or obstacles.
        const TPoint2D& i0 = p.interactions[0];
        double loss = crossingLoss_dB(src, i0, p.objectIndex[0]);
        std::complex<double> refl = walls_[p.objectIndex[0]].reflection;
        if (img.order == 2)
        {
            const TPoint2D& i1 = p.interactions[1];
            loss += crossingLoss_dB(i0, i1, p.objectIndex[0], p.objectIndex[1]);
            loss += crossingLoss_dB(i1, rx, p.objectIndex[1]);
            refl *= walls_[p.objectIndex[1]].reflection;
        }
        else
            loss += crossingLoss_dB(i0, rx, p.objectIndex[0]);

        p.length_m = std::hypot(img.position.x - rx.x, img.position.y - rx.y);
        p.departure_rad = angleOf(src, i0);
        p.arrival_rad = angleOf(rx, pLast);
        p.crossingLoss_dB = loss;
        p.gain = refl * friis / std::max(p.length_m, kMinDistance_m) * dB2amplitude(-loss);
        out.push_back(p);
    }

    // Single scattering, bistatic radar equation in amplitude: √σ·λ / ((4π)^1.5·d1·d2).
    for (size_t i = 0; i < scatterers_.size(); ++i)
    {
        const Scatterer& sc = scatterers_[i];
        const double d1 =
            std::max(std::hypot(sc.position.x - src.x, sc.position.y - src.y), kMinDistance_m);
        const double d2 =
            std::max(std::hypot(rx.x - sc.position.x, rx.y - sc.position.y), kMinDistance_m);
        PropagationPath p;
        p.kind = PathKind::Scattering;
        p.interactionCount = 1;
        p.interactions[0] = sc.position;
        p.objectIndex = {{int(i), -1}};
        p.length_m = d1 + d2;
        p.departure_rad = angleOf(src, sc.position);
        p.arrival_rad = angleOf(rx, sc.position);
        p.crossingLoss_dB = crossingLoss_dB(src, sc.position) + crossingLoss_dB(sc.position, rx);
        p.gain = std::polar(
            std::sqrt(sc.radarCrossSection_m2) * wavelength_m /
                (std::pow(4.0 * M_PI, 1.5) * d1 * d2) * dB2amplitude(-p.crossingLoss_dB),
            sc.phase_rad);
        out.push_back(p);
    }

    // Drop what is buried far below the strongest path (never the line of sight).
    double strongest = 0;
    for (const auto& p : out) strongest = std::max(strongest, std::abs(p.gain));
    const double floor = strongest * dB2amplitude(spec_.minPathGain_dB);
    out.erase(
        std::remove_if(
            out.begin() + 1, out.end(),
            [floor](const PropagationPath& p) { return std::abs(p.gain) < floor; }),
        out.end());

    for (auto& p : out) p.delay_s = p.length_m / kSpeedOfLight;
}

std::vector<PropagationPath> ChannelModel::computePaths(
    const TPoint2D& transmitter, const TPoint2D& receiver, double wavelength_m) const
{
    std::vector<PropagationPath> out;
    computePaths(imagesOf(transmitter), receiver, wavelength_m, out);
    return out;
}

}  // namespace mrpt_wifi::sim
