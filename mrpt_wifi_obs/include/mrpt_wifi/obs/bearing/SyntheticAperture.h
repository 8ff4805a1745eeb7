/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPoint2D.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/bearing/BearingEstimator.h>

#include <complex>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

/** Bearings from one antenna on a moving robot (the WSR Toolbox's synthetic aperture, arXiv
 * 2012.04174 / 2109.12205). A moving robot and a peer exchange packets; the product of the
 * channel each heard from the other cancels both oscillators' offsets, leaving twice the
 * propagation phase, 2·(2π/λ)·|peer − robot|. Over a trajectory with known displacement the
 * products form an aperture, and the peer's direction is the one whose predicted phases best
 * match them (Bartlett). */
namespace mrpt_wifi::sar
{
/** One exchange: where the moving robot's antenna was and the combined channel product. */
struct Exchange
{
    double time_s = 0;              //!< on the moving robot's clock
    mrpt::math::TPoint2D position;  //!< moving antenna in the trajectory's frame [m]
    std::complex<double> product;   //!< forward × reverse, subcarriers combined
};

/** Forward × reverse channel of one exchange between receive chain `moverRx` of the moving
 * robot and `peerRx` of the peer (stream 0), combined over the reported subcarriers: each
 * packet's delay slope (detection-time offset, not reciprocal) is measured from the rotation
 * between neighbouring subcarriers and removed, then the subcarriers are summed coherently.
 * Both frames must report the same subcarriers. std::nullopt (and `why`) otherwise. */
std::optional<std::complex<double>> combinedProduct(
    const CObservationWiFiCSI& heardByMover, const CObservationWiFiCSI& heardByPeer,
    unsigned moverRx, unsigned peerRx, std::string* why = nullptr);

/** The same for two preprocessed frames (CleanCsi row stream 0 × chain; both must keep each
 *  frame's absolute phase: no sampling-time-offset removal). */
std::optional<std::complex<double>> combinedProduct(
    const CleanCsi& heardByMover, const CleanCsi& heardByPeer, unsigned moverRx, unsigned peerRx,
    std::string* why = nullptr);

/** Unwraps a 16-bit counter in arrival order (a reset backwards by more than half the range
 *  counts as a wrap). */
std::vector<uint64_t> unwrapCounter16(const std::vector<uint16_t>& counters);

/** Index pairs (mover, peer) of frames with equal counters; a counter seen twice on one side
 * is used once (its first frame). */
std::vector<std::pair<size_t, size_t>> pairByCounter(
    const std::vector<uint64_t>& moverCounters, const std::vector<uint64_t>& peerCounters);

/** The senders' frame counters of frames in arrival order, unwrapped (firmwareCounter). */
std::vector<uint64_t> frameCounters(const std::vector<CObservationWiFiCSI::Ptr>& frames);

/** One exchange before positions are known: when the moving robot heard it, and the product. */
struct PairedProduct
{
    double time_s = 0;  //!< the moving robot's timestamp of the peer's packet
    std::complex<double> product;
};

/** The moving robot's frames from one peer paired with the peer's frames of the robot by
 * counter, each pair's combinedProduct() (pairs without one skipped). `pairs` (optional): how
 * many pairs matched. */
std::vector<PairedProduct> pairedProducts(
    const std::vector<CObservationWiFiCSI::Ptr>& heardByMover,
    const std::vector<CObservationWiFiCSI::Ptr>& heardByPeer, unsigned moverRx, unsigned peerRx,
    size_t* pairs = nullptr);

/** How well the peer's recording matches frames of one sender in the mover's recording: the
 * mean correlation of the two channels' amplitude across subcarriers over paired exchanges
 * (the channel is reciprocal, so the right sender correlates; about 0 for another one). */
double reciprocityScore(
    const std::vector<CObservationWiFiCSI::Ptr>& heardByMover,
    const std::vector<CObservationWiFiCSI::Ptr>& heardByPeer, unsigned moverRx, unsigned peerRx);

struct SarOptions
{
    double carrier_Hz = 5.54e9;          //!< centre frequency of the exchanges
    double azimuthStep_deg = 0.5;        //!< far-field grid
    double minApertureLength_m = 0.3;    //!< shorter paths give no estimate
    double minMotionPerPacket_m = 1e-4;  //!< below: the robot stands still, packet unused
    /** Candidate ranges of the near-field refinement around the far-field peak [m]. The
     * far-field model assumes a straight wavefront; at a few metres a 1 m path sees the
     * bearing turn by several degrees, which biases it. */
    std::vector<double> ranges_m = {1.5, 2, 2.5, 3, 3.5, 4, 5, 6, 8, 12};
    double refineHalfWidth_deg = 15;  //!< near-field search around the far-field peak
    /** The near-field search stays inside the far-field peak's main lobe (down to its first
     *  minima), so that behind an obstacle it cannot fit a nearby scatterer. Measured on the WSR
     *  development sets (OptiTrack): NLOS_Set_A's mean 7.7° to 6.8°, but LOS_Set_A's 2.7° to
     *  4.2° (the near-field bias correction reaches beyond the far-field lobe): off. */
    bool refineWithinLobe = false;
    double stdFloor_deg = 2.0;  //!< σ never below this (geometry of the path, multipath)
    /** σ grows as (coherenceReference / coherence)^coherenceExponent below the reference.
     * Chosen on the WSR development sets (LOS_Set_A, NLOS_Set_C): errors grow as coherence
     * falls (median 2° above 0.5, 10° below 0.3 with a tracking camera's positions). */
    double coherenceReference = 0.5;
    double coherenceExponent = 4.0;
    /** RMS error of the trajectory's positions over the aperture [m] (motion capture ≈ 0, a
     *  tracking camera ≈ 0.02): adds positionStdGain · positionStd_m / aperture length [rad] to
     *  σ in quadrature. */
    double positionStd_m = 0.0;
    double positionStdGain =
        4.0;  //!< chosen on simulated development rooms (96.7 % within 3σ at 2 cm)
    /** Products of unit magnitude (phase only) in the far- and near-field sums: behind an
     *  obstacle the strongest exchanges are the ones a reflection dominates. On the WSR
     *  development sets (OptiTrack) NLOS_Set_B's mean error fell from 29.8° to 26.0°,
     *  NLOS_Set_A's from 8.5° to 7.7°, LOS_Set_A's stayed 2.7°. */
    bool phaseOnly = true;
    /** Elevations of the peer above the aperture's plane [deg] whose far-field profiles are
     *  summed (the elevation-marginal profile): a planar path sees a peer at elevation ε with
     *  its phases scaled by cos ε. {0}: the plane only. {0, 20, 40, 60, 80} was measured on the
     *  WSR development sets: NLOS_Set_B better (mean 26° to 19°), NLOS_Set_A worse (7.7° to
     *  10.3°), so the plane alone stays the default. */
    std::vector<double> elevations_deg = {0};
    /** A local maximum of the far-field profile at least this fraction of the peak is a strong
     *  peak (SarEstimate::peaks). */
    double strongPeakFraction = 0.5;
    /** Strong peaks closer than this to a stronger one are the same lobe [deg]. */
    double peakSeparation_deg = 10;
    /** σ never below this with one strong peak / with several [deg], times (stdCoherence /
     *  coherence)² below stdCoherence. Fitted on the WSR development sets (LOS_Set_A,
     *  NLOS_Set_C, NLOS_Set_A and NLOS_Set_B L1–L5; OptiTrack and T265) for ≥ 97 % within 3σ
     *  in every set: behind obstacles a sharp peak is often 10–25° off (a path through or
     *  around the obstacle), which the main lobe's width does not show, while fewer strong
     *  peaks and a higher coherence go with smaller errors. */
    double onePeakStd_deg = 3.6;
    double severalPeaksStd_deg = 4.2;
    double stdCoherence = 0.6;
};

/** One local maximum of the far-field profile. */
struct SarPeak
{
    double azimuth_rad = 0;
    double power = 0;  //!< over the highest peak's, 0..1
    /** Probability that this peak, not the bearing, is the peer's direction (0 for the first):
     *  on the WSR development sets the second peak was nearer the truth than the first in
     *  29 % of bearings when its power was ≥ 0.6 (7 % below), the third nearer than both in
     *  18 %. */
    double weight = 0;
};

struct SarEstimate
{
    double azimuth_rad = 0;     //!< direction to the peer from `start`, trajectory frame
    double azimuthStd_rad = 0;  //!< 1σ
    double quality = 0;         //!< 0..1: 1 − (highest side peak / main peak) of the profile
    /** The azimuth mirrored across the path's main direction (from `start`; a near-field
     *  fit's peer reflected across that line) and the far-field profile's value there (0..1):
     *  near 1, the path was too straight to tell the peer from its mirror image. */
    double mirror_rad = 0;
    double mirrorRange_m = 0;  //!< from `start` (0: far field)
    double mirrorPower = 0;
    /** |Σ w·h·conj(model)| / Σ w·|h| at the best fit, 0..1: how much of the products' energy
     *  the fitted peer explains (position errors along the path lower it). */
    double coherence = 0;
    double range_m = 0;           //!< near-field range of the best fit (0: far field fitted best)
    size_t packetsUsed = 0;       //!< exchanges taken while moving
    double apertureLength_m = 0;  //!< path length over the used exchanges
    mrpt::math::TPoint2D start;   //!< position at the first used exchange
    double startTime_s = 0;
    /** Far-field Bartlett profile (elevation-marginal), normalised to its peak, from −180° in
     *  azimuthStep_deg. */
    std::vector<double> profile;
    /** The profile's strong peaks (SarOptions::strongPeakFraction), strongest first; the first
     *  is the one the bearing was refined from. */
    std::vector<SarPeak> peaks;
    /** Mean of the profile (normalised to its peak): near 1 a flat profile that points
     *  nowhere (WSR's profile variance). */
    double profileMean = 0;
    /** σ of the bearing's own direction, given it is the right one (main lobe, coherence,
     *  path); azimuthStd_rad also covers a direction that is wrong (SarOptions::
     *  onePeakStd_deg). */
    double lobeStd_rad = 0;
};

/** Bearing to the peer from exchanges sorted by time. std::nullopt with `whyNot` when the
 * robot did not move enough or no exchange has a usable product. */
std::optional<SarEstimate> estimateBearing(
    const std::vector<Exchange>& exchanges, const SarOptions& options, std::string& whyNot);

/** The synthetic aperture as a registered bearing estimator ("sar", bearing::createEstimator):
 * given one peer's frames heard by the moving robot over the last `aperture_s`, the peer's
 * recording of the robot's packets and the antenna's poses (EstimatorContext), the bearing to
 * the peer from the antenna's newest pose, in the antenna's frame (a near-field fit's peer
 * position is carried from the aperture's start to the newest pose). BearingProcessor feeds it
 * from a rawlog holding both recordings and odometry (Options::peerRecordings). */
class SyntheticApertureEstimator : public bearing::BearingEstimator
{
public:
    std::string name() const override { return "sar"; }
    std::string description() const override;
    std::vector<std::string> parameterKeys() const override;
    /** The frames of `aperture_s` seconds at a few hundred exchanges per second. */
    size_t framesWanted() const override { return kMaxFrames; }
    bool syntheticAperture() const override { return true; }
    double windowSpan_s() const override { return opts_.aperture_s; }

    bool estimate(
        const std::vector<const CleanCsi*>& frames, const bearing::EstimatorContext& ctx,
        bearing::BearingResult& result) override;

    /** The last estimate in the trajectory's frame (start, coherence, range, profile), or
     *  nullopt with lastWhyNot() saying why there was none. */
    const std::optional<SarEstimate>& lastEstimate() const { return last_; }
    const std::string& lastWhyNot() const { return whyNot_; }

    static constexpr size_t kMaxFrames = 8192;
    /** SarEstimate::mirrorPower from which a bearing is reported as mirror-ambiguous. */
    static constexpr double kMirrorAmbiguity = 0.8;

private:
    std::optional<SarEstimate> last_;
    std::string whyNot_;
    std::vector<Exchange> exchanges_;
};

}  // namespace mrpt_wifi::sar
