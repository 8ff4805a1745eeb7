/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/containers/yaml.h>
#include <mrpt/core/Clock.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

/** Bearing estimators: observation processors that turn preprocessed CSI into angles. */
namespace mrpt_wifi::bearing
{
/** One more direction a window's profile supports (folded like BearingResult::aoa_rad). */
struct AoaAlternative
{
    double aoa_rad = 0;
    /** Probability that this direction, not aoa_rad, is the transmitter's, from the model
     *  measured on the development rooms (alternativeWeight()); 0..1, the alternatives of one
     *  bearing sum to < 1 and aoa_rad keeps the rest. */
    double weight = 0;
    /** What the weight came from: the peak's power over the chosen one's (> 1: stronger) and,
     *  for angle × delay profiles, its path's delay minus the chosen path's [s] (NaN: none). */
    double relativePower = 0;
    double delayAfter_s = std::numeric_limits<double>::quiet_NaN();
};

/** Cap on the alternatives a bearing carries (the strongest by weight). */
constexpr size_t kMaxAoaAlternatives = 3;

/** What an estimator found for one transmitter. Angles in radians; AoA in the receive array's
 *  frame, AoD in the transmitter array's frame (DESIGN.md §6). */
struct BearingResult
{
    bool valid = false;
    double aoa_rad = 0;
    double aoaStd_rad = 0;
    /** Linear receive arrays: the mirror image of aoa_rad across the array axis, which fits the
     *  CSI equally well. aoa_rad is the candidate in the array's front half-plane. */
    double aoaMirror_rad = 0;
    bool aoaAmbiguous = false;
    /** Other directions the window's profile supports (a reflection stronger than the direct
     *  path, near endfire the rt-ac86u's 26 mm spacing aliasing the other endfire), folded like
     *  aoa_rad. The first (the heaviest) is in the scalar fields, the others in
     *  moreAoaAlternatives; aoaAlternatives() gives them all. aoaAlternativeWeight (0..1):
     *  AoaAlternative::weight. aoaStd_rad reaches the strongest ambiguous one;
     *  aoaDirectionStd_rad is the σ of aoa_rad's own direction, given it is the right one (for a
     *  consumer that weighs the directions as a mixture). Without an alternative: none, and
     *  aoaDirectionStd_rad == aoaStd_rad. */
    bool hasAoaAlternative = false;
    double aoaAlternative_rad = 0;
    double aoaAlternativeWeight = 0;
    double aoaDirectionStd_rad = 0;
    std::vector<AoaAlternative> moreAoaAlternatives;  //!< second and later, by weight
    /** The first alternative's evidence (AoaAlternative::relativePower, ::delayAfter_s). */
    double aoaAlternativeRelativePower = 0;
    double aoaAlternativeDelayAfter_s = std::numeric_limits<double>::quiet_NaN();
    /** Every direction the estimator weighed, kept or not (for measuring the weight model). */
    std::vector<AoaAlternative> aoaCandidates;

    /** All alternatives, the first from the scalar fields (empty without). */
    std::vector<AoaAlternative> aoaAlternatives() const
    {
        std::vector<AoaAlternative> all;
        if (!hasAoaAlternative) return all;
        all.push_back(
            {aoaAlternative_rad, aoaAlternativeWeight, aoaAlternativeRelativePower,
             aoaAlternativeDelayAfter_s});
        all.insert(all.end(), moreAoaAlternatives.begin(), moreAoaAlternatives.end());
        return all;
    }
    /** Stores `alts` (heaviest first): the first in the scalar fields, the rest after it. */
    void setAoaAlternatives(const std::vector<AoaAlternative>& alts)
    {
        hasAoaAlternative = !alts.empty();
        aoaAlternative_rad = hasAoaAlternative ? alts[0].aoa_rad : 0.0;
        aoaAlternativeWeight = hasAoaAlternative ? alts[0].weight : 0.0;
        aoaAlternativeRelativePower = hasAoaAlternative ? alts[0].relativePower : 0.0;
        aoaAlternativeDelayAfter_s =
            hasAoaAlternative ? alts[0].delayAfter_s : std::numeric_limits<double>::quiet_NaN();
        moreAoaAlternatives.assign(alts.size() > 1 ? alts.begin() + 1 : alts.end(), alts.end());
    }

    bool hasAod = false;
    double aod_rad = 0;
    double aodStd_rad = 0;
    double aodMirror_rad = 0;
    bool aodAmbiguous = false;

    bool hasDelay = false;
    double delay_s = 0;  //!< of the chosen path, relative to the frame's mean delay

    /** 0..1: fraction of the received power that one plane wave from the chosen direction
     *  explains (1 for a clean single path, low for diffuse multipath or noise). */
    double quality = 0;
    unsigned framesUsed = 0;
    unsigned pathsDetected = 0;  //!< signal-subspace dimension or peaks considered
};

/** A likelihood (or pseudo-spectrum) over bearing × delay, kept for pictures. 1-D estimators
 *  leave `delays_s` with a single 0 entry. */
struct BearingProfile
{
    std::vector<double> angles_rad;
    std::vector<double> delays_s;
    Eigen::MatrixXf values;  //!< [angle][delay], linear, ≥ 0
    std::string label;       //!< "Bartlett power", "MUSIC pseudo-spectrum", ...
    double peakAngle_rad = 0;
    double peakDelay_s = 0;
    bool hasPeak = false;
};

/** Options common to all estimators; each estimator reads the ones that apply to it (unknown
 *  keys are an error). Angles in degrees and delays in ns in configs (human-facing). */
struct EstimatorOptions
{
    unsigned angleBins = 180;   //!< `angle_bins`: grid over the search interval
    unsigned delayBins = 180;   //!< `delay_bins`
    double delayMin_ns = -100;  //!< `delay_min_ns`: delays are relative to the mean delay
    double delayMax_ns = 150;   //!< `delay_max_ns`
    /** `delay_decimation`: neighbouring subcarriers averaged before the 2-D profile's delay
     *  transform (1 = none; 2 halves its cost, < 0.5 dB loss within ±150 ns). */
    unsigned delayDecimation = 2;
    unsigned window = 1;           //!< `window`: recent frames combined per estimate
    unsigned frequencyGroups = 4;  //!< `frequency_groups`: sub-bands with their own wavelength
    bool refine = true;            //!< `refine`: grid-free polish of the chosen peak
    double stdFloor_deg = 0.5;     //!< `std_floor_deg`: model-error floor of the reported σ
    bool keepProfile = false;      //!< `keep_profile`: keep the last profile (for images)
    // Subspace methods
    unsigned maxPaths = 3;         //!< `max_paths`: cap on the signal-subspace dimension
    double subspaceThreshold = 8;  //!< `subspace_threshold`: eigenvalue / noise level ratio
    // Windowed SVD
    unsigned components = 1;  //!< `components`: principal components kept
    // SpotFi
    unsigned subcarrierStep = 4;        //!< `subcarrier_step`: decimation of the uniform grid
    unsigned smoothingLength = 16;      //!< `smoothing_length`: subcarriers per smoothed vector
    double directPathPowerRatio = 0.3;  //!< `direct_path_power_ratio`: peaks this strong compete
    // AoD
    std::string aodMethod = "bartlett";  //!< `aod_method`: bartlett | music
    // Synthetic aperture (one antenna on a moving robot)
    double aperture_s = 15;      //!< `aperture_s`: span of the robot's frames combined
    double minAperture_m = 0.3;  //!< `min_aperture_m`: shorter paths give no bearing
    double positionStd_m = 0;    //!< `position_std_m`: RMS error of the poses over the path
    unsigned moverChain = 0;     //!< `mover_chain`: the moving robot's receive chain
    unsigned peerChain = 0;      //!< `peer_chain`: the peer's receive chain

    /** Reads a YAML map; throws std::invalid_argument naming an unknown key or a bad value.
     *  `allowed`: keys this estimator understands. */
    void load(
        const mrpt::containers::yaml& params, const std::vector<std::string>& allowed,
        const std::string& estimatorName);
};

/** Geometry an estimator needs: the receive array and, for AoD, the transmitter's array. */
struct EstimatorContext
{
    const AntennaArray* rxArray = nullptr;
    /** Array of a transmitter (by MAC); nullptr if unknown (no AoD then). */
    std::function<const AntennaArray*(const MacAddress&)> txArrayOf;

    /** Synthetic aperture only: what the peer (by MAC) recorded of this robot's packets,
     *  oldest first (empty when nothing), and the receive antenna's pose (position, and the
     *  robot's heading plus the antenna's yaw) at a time, in any fixed frame; nullopt outside
     *  the known poses. */
    std::function<std::vector<const CleanCsi*>(const MacAddress&)> peerRecordingOf;
    std::function<std::optional<mrpt::math::TPose2D>(mrpt::Clock::time_point)> antennaPoseAt;
};

/** One bearing estimator ("observation processor"): named, configurable, reusable across frames
 *  (precomputed steering matrices per array × channel × grid; no allocation per frame once
 *  warm). Not thread-safe: one instance per thread. */
class BearingEstimator
{
public:
    virtual ~BearingEstimator() = default;

    /** Registered name ("aoa_only", "fft", ...). */
    virtual std::string name() const = 0;
    /** One line on what it does. */
    virtual std::string description() const = 0;
    /** Keys of EstimatorOptions it reads. */
    virtual std::vector<std::string> parameterKeys() const = 0;

    /** Applies a YAML map of options (see EstimatorOptions); throws std::invalid_argument. */
    void configure(const mrpt::containers::yaml& params);
    const EstimatorOptions& options() const { return opts_; }
    EstimatorOptions& options() { return opts_; }

    /** Frames the estimator wants from the transmitter's window. */
    virtual size_t framesWanted() const { return opts_.window; }

    /** Synthetic-aperture estimators combine one antenna's frames over the robot's motion
     *  with the peer's recording (EstimatorContext::peerRecordingOf, ::antennaPoseAt) and need
     *  each frame's absolute phase (no sampling-time-offset or power normalisation), over
     *  windowSpan_s() seconds. The others take frames while the robot hardly moves. */
    virtual bool syntheticAperture() const { return false; }
    virtual double windowSpan_s() const { return 0; }

    /** Estimates from the given frames of one transmitter (oldest first; all of one shape).
     *  Returns false (and result.valid = false) if it can't, e.g. too few antennas. */
    virtual bool estimate(
        const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx,
        BearingResult& result) = 0;

    /** The last profile, if `keep_profile` is on and the estimator makes one. */
    const BearingProfile* lastProfile() const { return hasProfile_ ? &profile_ : nullptr; }

protected:
    EstimatorOptions opts_;
    BearingProfile profile_;
    bool hasProfile_ = false;
};

/** Names of all estimators, in the order of the documentation. */
std::vector<std::string> estimatorNames();
/** The estimators that take an antenna array's frames: all but the synthetic aperture ("sar",
 *  one antenna on a moving robot with a peer's recording). */
std::vector<std::string> arrayEstimatorNames();
/** Creates an estimator by name with options; throws std::invalid_argument listing the known
 *  names for an unknown one. */
std::unique_ptr<BearingEstimator> createEstimator(
    const std::string& name, const mrpt::containers::yaml& params = mrpt::containers::yaml());

}  // namespace mrpt_wifi::bearing
