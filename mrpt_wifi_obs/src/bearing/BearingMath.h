/* mrpt_wifi — WiFi channel state information for MRPT.
 * Internal building blocks shared by the bearing estimators (not installed). */
#pragma once

#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <complex>
#include <functional>
#include <vector>

namespace mrpt_wifi::bearing::detail
{
/** Bearings searched: the array's search interval cut into `bins` steps. */
struct AngleGrid
{
    std::vector<double> angles;
    double lo = 0, step = 0;
    bool circular = false;  //!< 2-D arrays: the grid wraps around

    static AngleGrid make(const AntennaArray& array, size_t n, unsigned bins);
    size_t size() const { return angles.size(); }
    /** Angle at a fractional grid index (wrapped for circular grids). */
    double at(double index) const;
};

/** Centre frequency and subcarrier count of each of `groups` contiguous sub-bands. */
void groupFrequencies(
    const SubcarrierLayout& layout, unsigned groups, std::vector<double>& freqs,
    std::vector<double>& counts);

/** a^H R a for Hermitian R. */
double quadraticForm(const Eigen::MatrixXcd& R, const Eigen::VectorXcd& a);

/** Evaluates Σ_g a_g(θ)^H R_g a_g(θ) on an angle grid in one real matrix product per group:
 *  with |a_i| = 1, a^H R a = tr R + 2 Σ_{i<j} Re(conj(a_i) a_j R_ij), linear in the entries of R.
 */
class QuadraticFormGrid
{
public:
    void prepare(
        const AntennaArray& array, size_t n, const AngleGrid& grid,
        const std::vector<double>& groupFreqs);
    /** out[θ] = Σ_g a_g(θ)^H R_g a_g(θ). */
    void evaluate(const std::vector<Eigen::MatrixXcd>& R, Eigen::VectorXd& out);
    size_t elements() const { return n_; }

private:
    size_t n_ = 0;
    std::vector<Eigen::MatrixXd> basis_;  // [group]: angles × (1 + n(n−1))
    Eigen::VectorXd coeffs_;
};

/** Basis of |a(θ)^H v|² on an angle grid (steering at one frequency, unit-modulus elements):
 *  row θ is [1, 2 Re w_01, −2 Im w_01, 2 Re w_02, ...], w_ij = conj(a_i) a_j, i < j, so that
 *  basis · c = Σ_v |a^H v|² for c the addOuterProductCoefficients() of the vectors v. */
Eigen::MatrixXf quadraticFormBasis(
    const AntennaArray& array, size_t n, const AngleGrid& grid, double frequency_Hz);

/** Adds to c (1 + n(n−1) values) the coefficients of v v^H in quadraticFormBasis()'s order:
 *  |v|², then Re and Im of v_i conj(v_j) for i < j. */
inline void addOuterProductCoefficients(const std::complex<float>* v, Eigen::Index n, float* c)
{
    Eigen::Index k = 1;
    for (Eigen::Index i = 0; i < n; ++i)
    {
        c[0] += std::norm(v[i]);
        for (Eigen::Index j = i + 1; j < n; ++j, k += 2)
        {
            c[k] += v[i].real() * v[j].real() + v[i].imag() * v[j].imag();
            c[k + 1] += v[i].imag() * v[j].real() - v[i].real() * v[j].imag();
        }
    }
}

/** Σ_g a_g(θ)^H R_g a_g(θ) at one angle, exact (group centre frequencies). */
double groupedForm(
    const AntennaArray& array, size_t n, double theta, const std::vector<double>& groupFreqs,
    const std::vector<Eigen::MatrixXcd>& R);

/** Maximises f on [a, b] by golden-section search. */
double goldenMaximize(const std::function<double(double)>& f, double a, double b, int iterations);

/** Offset in [−0.5, 0.5] of the vertex of the parabola through (−1, ym), (0, y0), (1, yp). */
double parabolicOffset(double ym, double y0, double yp);

/** Indices of local maxima of a 1-D spectrum, strongest first (at most `maxPeaks`). */
std::vector<size_t> findPeaks1D(const Eigen::VectorXd& v, bool circular, size_t maxPeaks);
/** Grid peak refined by a parabola on log values; returns a fractional index. */
double refinePeak1D(const Eigen::VectorXd& v, size_t i, bool circular);

/** Reported standard deviation [rad]: σ² = σ_CRB² + floor² + (¼·beamwidth·√((1−q)/q))², capped
 *  at 90°: the Cramér–Rao bound at the SNR the covariance shows (strongest eigenvalue over the
 *  rest), a model-error floor (calibration residuals), and a multipath term from the power the
 *  chosen plane wave leaves unexplained (quality q). Where the covariance is nearly one spatial
 *  signature (effective rank (tr R)²/‖R‖² below 2) the unexplained power 1 − q is measured
 *  against what a random field leaves (1 − randomFieldQuality()), fully at rank 1: a few
 *  antennas fit any single vector well, so a coherent reflection hides in a high q (issue 54:
 *  3 antennas at 20 MHz, 86 % of real bearings within 3σ before). */
double bearingStd(
    const AntennaArray& array, size_t n, double theta, const std::vector<Eigen::MatrixXcd>& R,
    const std::vector<double>& groupFreqs, const std::vector<double>& groupCounts,
    double snapshotsPerSubcarrier, double quality, double floor_rad);

/** Mean Bartlett quality the best direction reaches on a random single-snapshot field
 *  (i.i.d. complex Gaussian element values) for the first n elements of `array` at
 *  `frequency_Hz`: what "one plane wave explains q of the power" means by chance. Deterministic
 *  (fixed pseudo-random vectors), cached per geometry. */
double randomFieldQuality(const AntennaArray& array, size_t n, double frequency_Hz);

/** Bartlett quality: Σ_g a^H R_g a / (n · Σ_g tr R_g) ∈ [0, 1]. */
double bartlettQuality(double power, const std::vector<Eigen::MatrixXcd>& R, size_t n);

/** Sums the group covariances of several frames (receive side or transmit side). */
void sumCovariances(
    const std::vector<const CleanCsi*>& frames, unsigned groups, bool transmitSide,
    std::vector<Eigen::MatrixXcd>& out);

/** Noise-subspace projectors per group: Π_g = E_n E_n^H from the eigenvectors of R_g below
 *  the `signalDim` strongest. */
void noiseProjectors(
    const std::vector<Eigen::MatrixXcd>& R, unsigned signalDim, std::vector<Eigen::MatrixXcd>& out);

/** Signal-subspace dimension: eigenvalues above `threshold` × noise level (the mean of the
 *  smallest), at least 1 and at most min(maxPaths, n − 1). */
unsigned signalDimension(
    const Eigen::VectorXd& eigenvaluesAscending, double threshold, unsigned maxPaths);

/** Eigenvalues of a Hermitian matrix and the eigenvectors of its few largest ones, without
 *  the cost of all eigenvectors: Householder tridiagonalisation (T real), T's eigenvalues by
 *  QR, the wanted eigenvectors of T by inverse iteration (re-orthogonalised within clusters of
 *  close eigenvalues, as LAPACK's dstein) taken back through the reflections (zunmtr). Same
 *  results as Eigen::SelfAdjointEigenSolver up to rounding and each vector's phase. */
class TopEigenvectors
{
public:
    void compute(const Eigen::MatrixXcd& A);
    /** All eigenvalues, ascending. */
    const Eigen::VectorXd& eigenvalues() const { return eigenvalues_; }
    /** Orthonormal eigenvectors of the `count` largest eigenvalues, in the same (ascending)
     *  order: column c belongs to eigenvalues()[n − count + c]. */
    const Eigen::MatrixXcd& eigenvectors(Eigen::Index count);

private:
    Eigen::Tridiagonalization<Eigen::MatrixXcd> tri_;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es_;
    Eigen::VectorXd eigenvalues_, sub_, lu_d_, lu_dl_, lu_du_, lu_du2_, x_;
    std::vector<int> pivot_;
    Eigen::MatrixXd Z_;
    Eigen::MatrixXcd V_;
};

/** 2-D Bartlett (matched-filter) power over bearing × delay, summed over streams and frames:
 *  P(θ, τ) = Σ_m |a(θ)^H H_m d(τ)|², d_k(τ) = e^{+j2π k Δf τ}, a at the centre frequency.
 *
 * Cost per frame: (1) `decimation` neighbouring subcarriers are averaged first (a filter
 * cos(πΔfτ)-like, > 0.95 across ±150 ns for 2, at their mean k, so the phase stays exact);
 * (2) Y = H_dec · D, one complex product; (3) per delay the 4×4 receive covariance of the
 * streams' y_m(τ), whose entries make P(·, τ) through a real product with the same
 * quadratic-form basis as QuadraticFormGrid (5× fewer flops than beamforming every stream).
 *
 * P is linear in the per-delay covariance entries (the coefficients C, (1 + n(n−1)) × delays),
 * so a window's profile is B · Σ_frames C_f: each frame's C_f is kept with the frame
 * (CleanCsi::derived), and an estimate over a sliding window computes only the new frame's
 * terms and one product. */
class AngleDelayProfile
{
public:
    void prepare(
        const AntennaArray& array, size_t nRx, const SubcarrierLayout& layout,
        const AngleGrid& grid, const std::vector<double>& delays_s, unsigned decimation);
    void reset();
    /** Adds nStreams × nRx rows of CSI on the layout's subcarriers (row = stream·nRx + rx). */
    void accumulate(const Eigen::MatrixXcf& H, unsigned nStreams);
    /** Adds a preprocessed frame, its terms computed once per frame (cached with it). */
    void accumulate(const CleanCsi& frame);
    /** P(θ, τ) of what was accumulated since reset(). */
    const Eigen::MatrixXf& power();

private:
    /** The frame's coefficients C (basis coefficients × delays). */
    void terms(const Eigen::MatrixXcf& H, unsigned nStreams, Eigen::MatrixXf& C);

    size_t nRx_ = 0;
    uint64_t cacheOwner_ = 0;  //!< CleanCsi::derived() key of this configuration
    std::vector<std::pair<Eigen::Index, Eigen::Index>> groups_;  // [begin, end) layout indices
    Eigen::MatrixXf B_;   // angles × (1 + n(n−1)) quadratic-form basis
    Eigen::MatrixXcf D_;  // decimated subcarriers × delays
    Eigen::MatrixXcf Hd_, Y_;
    Eigen::MatrixXf C_;     // one frame's coefficients (uncached frames)
    Eigen::MatrixXf Csum_;  // Σ of the accumulated frames' coefficients
    Eigen::MatrixXf P_;
    bool powerValid_ = false;
};

/** Location of the maximum of a 2-D map with parabolic (log) refinement along each axis. */
struct Peak2D
{
    size_t i = 0, j = 0;
    double fi = 0, fj = 0;  //!< fractional indices
    float value = 0;
};
Peak2D refinePeak2D(const Eigen::MatrixXf& P, size_t i, size_t j, bool circularRows);
/** Local maxima (8-neighbourhood) of a 2-D map, strongest first. */
std::vector<Peak2D> findPeaks2D(const Eigen::MatrixXf& P, bool circularRows, size_t maxPeaks);

/** Per-group covariance of the CSI matched to one delay: y_{m,g} = Σ_{k∈g} h_{m,k} e^{j2πkΔfτ},
 *  R_g += Σ_m y y^H. Used to polish a 2-D peak's bearing with the wideband model. */
void delayFilteredCovariances(
    const std::vector<const CleanCsi*>& frames, double delay_s, unsigned groups,
    std::vector<Eigen::MatrixXcd>& R);

/** Weight of an alternative direction: the probability that it, not the chosen bearing, is the
 *  transmitter's, by a logistic model of what predicts the chosen one being wrong, fitted on
 *  the development rooms (docs/evaluation.md, "Several directions, weighed"): its peak's power
 *  over the chosen one's (`relativePower`), the chosen direction's quality (the power share a
 *  plane wave explains) and, for angle × delay profiles, the delay of its path after the
 *  chosen one's (`delayAfter_s`; NaN: the profile has none). */
double alternativeWeight(double relativePower, double delayAfter_s, double quality);
/** Alternatives lighter than this are dropped, unless stronger than the reported direction
 *  (a reflection stronger than the direct path is always carried, however unlikely). */
constexpr double kMinAlternativeWeight = 0.01;
/** Floor of a carried alternative's weight (readers require a weight > 0). */
constexpr double kAlternativeWeightFloor = 0.001;
/** The alternatives together leave the chosen direction at least 1 − this. */
constexpr double kMaxAlternativesShare = 0.6;

}  // namespace mrpt_wifi::bearing::detail
