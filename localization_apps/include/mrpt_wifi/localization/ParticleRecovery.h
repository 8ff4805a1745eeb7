/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mrpt_wifi::localization
{
/** When and how fast a particle filter re-seeds particles (section `[ParticleRecovery]`). */
struct ParticleRecoveryOptions
{
    /** `rate_hz`: while recovering, a step of dt re-seeds the fraction 1 − exp(−rate·dt) of the
     *  particles (at most half). 0: never. */
    double rate_hz = 1.0;
    /** `window_s`: the bearings of this last stretch are judged. */
    double window_s = 2.0;
    /** `min_agreement`: recovering while fewer than this share of the window's bearings lie
     *  within 3σ of the estimate (a handful disagree by chance: outliers, multipath). */
    double minAgreement = 0.5;
    /** `max_std_deg`: only bearings this sharp (reported σ) are judged: a wide one agrees with
     *  almost any pose and would hide a lost filter. */
    double maxStd_deg = 10.0;

    /** Missing keys keep their value; throws std::invalid_argument naming a bad one. */
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& cfg, const std::string& section);
    std::string asString() const;
};

/** Recovery of a particle filter that has lost the robot (augmented-MCL-like random particle
 *  injection, driven by the bearings): the bearings of each step are checked against the
 *  filter's estimate after the previous step; while most of a window's bearings disagree with
 *  it, or it lies outside the map's area, each step's action re-seeds a share of the particles
 *  over the area (withReseeding()). Needs the map's area (where to re-seed); without one it
 *  never recovers. The same object serves wifi-pf-localization and wifi-localize, with and
 *  without odometry.
 *
 *  Per filter step: setEstimate() with the estimate after the previous step, checkBearing() for
 *  each bearing of this step, then reseedFraction(t, dt) for the step's action. */
class ParticleRecovery
{
public:
    /** `map` is kept by reference (may be null: never recovers). */
    ParticleRecovery(const ParticleRecoveryOptions& options, const CWiFiBearingMap* map);

    void setEstimate(const mrpt::math::TPose2D& estimate) { estimate_ = estimate; }
    void checkBearing(double t_s, const CObservationWiFiBearing& b);
    /** The share of particles to re-seed in a step at `t_s` of `dt_s` seconds (0: none). */
    double reseedFraction(double t_s, double dt_s);
    /** Radius of the re-seeding jumps: the area's diagonal, so from anywhere inside it a jump
     *  reaches all of it. */
    double reseedRadius_m() const;
    /** A new run of the filter: forget the estimate and the window. */
    void reset();

    bool recovering() const { return recovering_; }
    size_t recoverySteps() const { return steps_; }
    size_t recoveryEpisodes() const { return episodes_; }
    /** Share of the window's bearings that agree with the estimate (NaN: none). */
    double agreement() const;

private:
    ParticleRecoveryOptions o_;
    const CWiFiBearingMap* map_;
    std::optional<mrpt::math::TPose2D> estimate_;
    std::deque<std::pair<double, bool>> checks_;  //!< (time, agrees)
    bool recovering_ = false;
    size_t steps_ = 0, episodes_ = 0;
};

/** `action` with the fraction `reseedFraction` of its pose change replaced by re-seeding jumps:
 *  its pose change as 1000 equally weighted samples (MRPT's filter draws each particle's step
 *  from them), that fraction of them uniform in a disc of radius `radius_m` (rotation-invariant,
 *  so uniform in the world frame too) with a uniform heading change; the rest drawn from the
 *  original pose change. Jumps landing outside the map's area die at the next update. Samples
 *  come from MRPT's global random generator. */
mrpt::obs::CActionRobotMovement2D withReseeding(
    const mrpt::obs::CActionRobotMovement2D& action, double reseedFraction, double radius_m);

/** Summary line: "N episodes, M steps re-seeding particles". */
std::string recoverySummary(const ParticleRecovery& r);

/** Summary line of a map's area and a filter's estimates: "x A..B y C..D m, N estimates outside
 *  it"; empty when the map has no area. */
std::string areaSummary(
    const CWiFiBearingMap& map, const std::vector<mrpt::math::TPose2D>& estimates);
/** The same line from a count of estimates outside the area kept while running. */
std::string areaSummary(const CWiFiBearingMap& map, uint64_t estimatesOutside);

}  // namespace mrpt_wifi::localization
