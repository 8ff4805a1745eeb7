/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPoint2D.h>
#include <mrpt_wifi/sim/Scenario.h>

#include <array>
#include <complex>
#include <vector>

namespace mrpt_wifi::sim
{
/** Speed of light in vacuum [m/s]. */
constexpr double kSpeedOfLight = 299792458.0;

enum class PathKind : uint8_t
{
    LineOfSight,
    Reflection,  //!< specular, via 1 or 2 walls (image method)
    Scattering   //!< via one point scatterer
};
const char* toString(PathKind k);

/** One propagation path between the transmitter and receiver reference points (2-D).
 *
 * Angles are world-frame directions: `departure_rad` is the direction in which the ray leaves
 * the transmitter, `arrival_rad` the direction *from the receiver towards* where the ray comes
 * from (for line of sight: towards the transmitter), the convention of DESIGN.md §5. */
struct PropagationPath
{
    PathKind kind = PathKind::LineOfSight;
    uint8_t interactionCount = 0;  //!< reflections or scatterings (0 for line of sight)
    std::array<mrpt::math::TPoint2D, 2> interactions;  //!< points, transmitter side first
    std::array<int, 2> objectIndex{{-1, -1}};  //!< wall (or scatterer) index per interaction
    double length_m = 0;                       //!< unfolded length
    double delay_s = 0;                        //!< length / c
    double departure_rad = 0;
    double arrival_rad = 0;
    /** Complex amplitude at the centre wavelength: free-space (or bistatic radar) spreading,
     *  reflection coefficients, crossing losses; without the propagation phase e^{-j2πfτ}. */
    std::complex<double> gain{0, 0};
    double crossingLoss_dB = 0;  //!< walls and obstacles crossed on the way
};

/** Ray paths of a 2-D scene: line of sight, specular reflections up to 2nd order by the image
 *  method, single scattering from point scatterers; walls and obstacles crossed attenuate. */
class ChannelModel
{
public:
    ChannelModel() = default;
    explicit ChannelModel(const Scenario& sc);
    ChannelModel(
        std::vector<Wall> walls, std::vector<Obstacle> obstacles, std::vector<Scatterer> scatterers,
        PropagationSpec spec);

    /** Mirror images of one transmitter position: computed once per static transmitter. */
    struct ImageSet
    {
        mrpt::math::TPoint2D source;
        struct Image
        {
            mrpt::math::TPoint2D position;
            std::array<int, 2> walls{{-1, -1}};  //!< reflection sequence, transmitter side first
            uint8_t order = 0;
        };
        std::vector<Image> images;  //!< orders 1..maxReflectionOrder
    };
    ImageSet imagesOf(const mrpt::math::TPoint2D& transmitter) const;

    /** All paths from the transmitter to `receiver` (cleared first; no allocation once `out`
     *  has grown). Paths weaker than minPathGain_dB below the strongest are dropped; the line
     *  of sight is always first, even when blocked by obstacles. */
    void computePaths(
        const ImageSet& tx, const mrpt::math::TPoint2D& receiver, double wavelength_m,
        std::vector<PropagationPath>& out) const;

    /** Convenience: images computed on the fly. */
    std::vector<PropagationPath> computePaths(
        const mrpt::math::TPoint2D& transmitter, const mrpt::math::TPoint2D& receiver,
        double wavelength_m) const;

    /** Total loss [dB] of walls and obstacles crossed by the segment a→b, ignoring the walls
     *  listed in `skipWalls` (the ones the ray reflects on at its ends). */
    double crossingLoss_dB(
        const mrpt::math::TPoint2D& a, const mrpt::math::TPoint2D& b, int skipWallA = -1,
        int skipWallB = -1) const;

    const std::vector<Wall>& walls() const { return walls_; }
    const PropagationSpec& spec() const { return spec_; }

private:
    std::vector<Wall> walls_;
    std::vector<Obstacle> obstacles_;
    std::vector<Scatterer> scatterers_;
    PropagationSpec spec_;
};

/** Mirror image of a point across the infinite line through a wall. */
mrpt::math::TPoint2D mirrorAcross(const Wall& w, const mrpt::math::TPoint2D& p);

}  // namespace mrpt_wifi::sim
