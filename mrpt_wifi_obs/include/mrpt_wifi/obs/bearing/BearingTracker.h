/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPose2D.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/MacAddress.h>

#include <map>
#include <optional>
#include <vector>

namespace mrpt_wifi::bearing
{
/** One direction a window's CSI supports (receive array frame, any of the two mirror images
 *  of a linear array) and how strongly, relative to the strongest (0..1]. */
struct BearingCandidate
{
    double theta_rad = 0;
    double relativePower = 1;
};

/** Per-transmitter bearing tracks over time.
 *
 * A window alone cannot always tell which of the directions its CSI supports is the direct
 * path: near endfire the rt-ac86u's 26 mm spacing (λ/2 at 5.775 GHz) makes both endfires
 * nearly equal, so a window may put a transmitter at one endfire while it is at the other. The
 * stream can tell: a linear array measures the angle to its axis, which moves continuously as
 * the robot moves — by at most the robot's rotation plus translation / range between two
 * windows — and never jumps from one endfire to the other. So each transmitter keeps a track
 * of that angle (Kalman filter on the bearing folded into the array's front half-plane; a 2-D
 * array's full bearing, turned by the odometry's rotation). Between windows the track's
 * variance grows by the odometry increment (|Δyaw|² for a linear array, which can't tell in
 * which direction the rotation moves the folded angle, plus (Δs / `assumedRange_m`)², the
 * range being unknown); without odometry by `noOdometryRate`² Δt. A window that says itself
 * it can't tell (σ beyond `ambiguousStd_rad`) and whose bearing falls outside the track's
 * gate while another direction it supports falls inside is replaced by that one (for a linear
 * array only a bearing near one endfire by one near the other). A sure window is never
 * replaced: a track that had locked onto the wrong endfire would swap every right window
 * away, and each swap would confirm it. A window with nothing inside the gate keeps its own
 * bearing, counts as a miss (if it is sure) and, if the track is narrow, gets a σ that reaches
 * the track; `maxMisses` misses in a row start the track over from the window's bearing. Only
 * a sure window starts a track. Not thread-safe. */
class BearingTracker
{
public:
    struct Options
    {
        double assumedRange_m = 2.0;  //!< translation Δs changes a bearing by ≤ Δs / range
        /** Unmodelled bearing change [rad/√s]: with and without odometry. */
        double processNoise = 5.0 * M_PI / 180;
        double noOdometryRate = 45.0 * M_PI / 180;
        double gateSigmas = 3.0;                //!< the gate, in σ of the predicted difference
        double minCandidatePower = 0.3;         //!< other directions weaker than this are ignored
        double minStd_rad = 1.0 * M_PI / 180;   //!< floor of a window's σ in the update
        double maxStd_rad = 10.0 * M_PI / 180;  //!< cap of a window's σ in the update
        double maxTrackStd_rad = 12.0 * M_PI / 180;  //!< a wider track widens no σ
        unsigned minHits = 3;                        //!< windows a track needs before it decides
        unsigned maxMisses = 3;                      //!< misses in a row that start the track over
        /** A window with a σ beyond this says it can't tell: its miss doesn't count, it
         *  starts no track, and only such a window is swapped for the track's candidate. */
        double ambiguousStd_rad = 30.0 * M_PI / 180;
        /** Linear arrays: the track swaps a bearing only for one near the other endfire,
         *  both at least this far from broadside (the aliasing the array's spacing allows). */
        double endfireZone_rad = 55.0 * M_PI / 180;
        double forgetAfter_s = 3.0;  //!< a track unseen this long starts over
    };

    /** What the track says about one window. */
    struct Decision
    {
        size_t chosen = 0;            //!< index into the candidates
        bool confident = false;       //!< the track was established and narrow
        bool miss = false;            //!< no candidate within the gate
        double predicted_rad = 0;     //!< the track's prediction (receive array frame)
        double trackStd_rad = 0;      //!< its σ (prediction)
        double disagreement_rad = 0;  //!< chosen candidate ↔ prediction (folded)
        double support = 0;           //!< hits of the track before this window
    };

    BearingTracker() = default;
    explicit BearingTracker(Options options) : opts_(options) {}
    Options& options() { return opts_; }

    /** Updates transmitter `tx`'s track with one window at time t_s. `pose`: robot odometry
     *  at t_s (nullopt: none). `candidates`: the estimator's bearing first, then others the
     *  window supports (any order). `std_rad`: the estimator's σ. */
    Decision update(
        const MacAddress& tx, double t_s, const std::optional<mrpt::math::TPose2D>& pose,
        const AntennaArray& rx, const std::vector<BearingCandidate>& candidates, double std_rad);

    void clear() { tracks_.clear(); }

private:
    struct Track
    {
        double angle = 0;  //!< folded (linear array, relative to broadside) or full [rad]
        double var = 0;
        unsigned hits = 0, misses = 0;
        double t_s = 0;
        std::optional<mrpt::math::TPose2D> pose;
    };

    Options opts_;
    std::map<MacAddress, Track> tracks_;
};

}  // namespace mrpt_wifi::bearing
