/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPoint2D.h>

#include <Eigen/Core>
#include <complex>
#include <string>
#include <vector>

namespace mrpt_wifi
{
/** Speed of light in vacuum [m/s]. */
constexpr double kSpeedOfLightMps = 299792458.0;

/** A planar antenna array: element phase centres in the array's own frame (x forward / boresight,
 *  y left, metres), in port order (element i is receive core i, or transmit stream i).
 *
 * Geometry lives in files, one per device (share/arrays/NAME.yaml):
 * \code
 * name: rt-ac86u
 * description: free text
 * elements:          # [x, y] metres, port order
 *   - [0.0, 0.0]
 *   - [0.0, 0.052]
 * cores: [0, 1]      # optional: the receive core of each element (default: element i = core i)
 * \endcode
 *
 * `cores` is for a receiver that reports only some of its cores (an RT-AC86U with core mask
 * 0xb: `cores: [0, 1, 3]`) or whose antennas are wired in another order. Element i then reads
 * the CSI of core cores[i]; calibration files follow the elements' order.
 *
 * Steering convention (DESIGN.md §5, the simulator's too): a plane wave arriving from direction
 * θ (u = (cos θ, sin θ), pointing from the array towards the source) reaches element i with phase
 * +2π f/c · (a_i · u) relative to the origin. Each subcarrier uses its own frequency f_k.
 *
 * A linear array (all elements on one line) only measures the angle to its axis: θ and its mirror
 * across the axis give identical CSI. Estimators then search the half-plane
 * [broadside − 90°, broadside + 90°] and report both candidates (mirrorOf()).
 */
struct AntennaArray
{
    std::string name;
    std::string description;
    std::vector<mrpt::math::TPoint2D> elements;
    /** Receive core of each element (element i reads core cores[i]); empty: element i is core
     *  i. */
    std::vector<unsigned> cores;
    std::string sourcePath;  //!< file it came from ("" if built in code or from text)

    size_t size() const { return elements.size(); }
    /** Receive core that element i reads. */
    unsigned coreOf(size_t i) const { return i < cores.size() ? cores[i] : unsigned(i); }

    /** One isotropic element at the origin (a single-antenna device). */
    static AntennaArray singleElement();
    /** Loads an array file; throws std::runtime_error naming the file and the problem. */
    static AntennaArray fromYamlFile(const std::string& path);
    /** As fromYamlFile() for a value a user wrote: a path relative to `baseDir` (empty: the
     *  working directory) or a shipped array by name (`rt-ac86u`, from the data folder), by
     *  config::resolveConfigPath()'s rules. `what` names the option or key in errors. */
    static AntennaArray fromFileOrName(
        const std::string& value, const std::string& what, const std::string& baseDir = {});
    /** As fromYamlFile() from YAML text; `displayName` is used in messages. */
    static AntennaArray fromYamlText(
        const std::string& text, const std::string& displayName = "<text>");
    /** Writes the array in the file format above. */
    std::string asYamlText() const;

    /** The first n elements (a receiver using fewer chains than the array has). */
    AntennaArray firstElements(size_t n) const;

    /** True if all elements lie on one line (within `tolerance_m`); one element counts too. */
    bool isLinear(double tolerance_m = 1e-6) const;
    /** Direction [rad] of the array's line for a linear array (the first-to-farthest element);
     *  0 for a single element. Meaningless for 2-D arrays. */
    double axisDirection() const;
    /** Direction [rad] that the unambiguous search half-plane is centred on: the broadside
     *  (axis − 90°) for a linear array, folded to |·| ≤ 90° so the array's front is used;
     *  0 for 2-D arrays. */
    double broadside() const;
    /** Mirror image of θ across the array axis (2·axis − θ, wrapped to (−π, π]); θ itself for 2-D
     *  arrays. */
    double mirrorOf(double theta) const;
    /** Search interval [lo, hi) of bearings: broadside ± 90° for linear arrays, [−π, π) else. */
    std::pair<double, double> searchInterval() const;

    /** Path-length advance [m] of element i towards a source in direction θ: a_i · u(θ). */
    double projection(size_t i, double theta) const;
    /** Steering phase [rad] of element i at frequency f: 2π f/c · (a_i · u(θ)). */
    double steeringPhase(size_t i, double theta, double frequency_Hz) const;
    /** Steering vector (first `n` elements, n = 0: all) at one frequency: e^{+j·phase}. */
    Eigen::VectorXcd steeringVector(double theta, double frequency_Hz, size_t n = 0) const;
    /** Steering matrix [element][angle] for an angle grid at one frequency (n elements). */
    Eigen::MatrixXcd steeringMatrix(
        const std::vector<double>& thetas, double frequency_Hz, size_t n = 0) const;
    /** Steering vectors of one angle over many frequencies, [element][frequency]: the wideband
     *  array response (each subcarrier with its own wavelength). */
    Eigen::MatrixXcd wideband(
        double theta, const std::vector<double>& frequencies_Hz, size_t n = 0) const;

    /** Cramér–Rao bound [rad] on the bearing of one path in white noise with an unknown complex
     *  gain per snapshot: var(θ) ≥ 1 / (2·SNR·Σ_k Σ_i (ψ_ik − ψ̄_k)²), ψ_ik = ∂phase_i/∂θ at
     *  frequency f_k, repeated `snapshotsPerFrequency` times (streams × frames). `snr` is the
     *  linear per-element, per-subcarrier SNR. */
    double aoaCramerRaoBound(
        double theta, const std::vector<double>& frequencies_Hz, double snr,
        double snapshotsPerFrequency = 1, size_t n = 0) const;
};

/** Wraps an angle to (−π, π]. */
double wrapAngle(double a);
/** |a − b| wrapped to [0, π]. */
double angleDistance(double a, double b);

}  // namespace mrpt_wifi
