/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include "BearingMath.h"

#include <mrpt_wifi/obs/Subcarriers.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <tuple>

namespace mrpt_wifi::bearing::detail
{
AngleGrid AngleGrid::make(const AntennaArray& array, size_t n, unsigned bins)
{
    AngleGrid g;
    const AntennaArray used = array.firstElements(n);
    const auto [lo, hi] = used.searchInterval();
    g.circular = !(used.size() >= 2 && used.isLinear());
    g.lo = lo;
    g.step = (hi - lo) / bins;
    g.angles.resize(bins);
    for (unsigned i = 0; i < bins; ++i) g.angles[i] = lo + i * g.step;
    return g;
}

double AngleGrid::at(double index) const
{
    const double a = lo + index * step;
    return circular ? wrapAngle(a) : a;
}

void groupFrequencies(
    const SubcarrierLayout& layout, unsigned groups, std::vector<double>& freqs,
    std::vector<double>& counts)
{
    freqs.assign(groups, 0.0);
    counts.assign(groups, 0.0);
    for (unsigned g = 0; g < groups; ++g)
    {
        const auto [b, e] = CleanCsi::groupRange(layout.size(), groups, g);
        for (size_t j = b; j < e; ++j) freqs[g] += layout.frequencies_Hz[j];
        counts[g] = double(e - b);
        freqs[g] = e > b ? freqs[g] / double(e - b) : layout.centerFrequency_Hz;
    }
}

double quadraticForm(const Eigen::MatrixXcd& R, const Eigen::VectorXcd& a)
{
    return (a.adjoint() * R * a)(0, 0).real();
}

// ---------------------------------------------------------------------------------------------
void QuadraticFormGrid::prepare(
    const AntennaArray& array, size_t n, const AngleGrid& grid,
    const std::vector<double>& groupFreqs)
{
    n_ = n;
    const size_t nb = 1 + n * (n - 1);
    basis_.assign(groupFreqs.size(), Eigen::MatrixXd(grid.size(), nb));
    for (size_t g = 0; g < groupFreqs.size(); ++g)
        for (size_t t = 0; t < grid.size(); ++t)
        {
            const Eigen::VectorXcd a = array.steeringVector(grid.angles[t], groupFreqs[g], n);
            auto row = basis_[g].row(Eigen::Index(t));
            row[0] = 1.0;
            size_t c = 1;
            for (size_t i = 0; i < n; ++i)
                for (size_t j = i + 1; j < n; ++j)
                {
                    const std::complex<double> w =
                        std::conj(a[Eigen::Index(i)]) * a[Eigen::Index(j)];
                    row[Eigen::Index(c++)] = 2 * w.real();
                    row[Eigen::Index(c++)] = -2 * w.imag();
                }
        }
    coeffs_.resize(Eigen::Index(nb));
}

void QuadraticFormGrid::evaluate(const std::vector<Eigen::MatrixXcd>& R, Eigen::VectorXd& out)
{
    out.setZero(basis_.empty() ? 0 : basis_[0].rows());
    for (size_t g = 0; g < basis_.size() && g < R.size(); ++g)
    {
        const auto& Rg = R[g];
        coeffs_[0] = Rg.trace().real();
        Eigen::Index c = 1;
        for (Eigen::Index i = 0; i < Eigen::Index(n_); ++i)
            for (Eigen::Index j = i + 1; j < Eigen::Index(n_); ++j)
            {
                coeffs_[c++] = Rg(i, j).real();
                coeffs_[c++] = Rg(i, j).imag();
            }
        out.noalias() += basis_[g] * coeffs_;
    }
}

double groupedForm(
    const AntennaArray& array, size_t n, double theta, const std::vector<double>& groupFreqs,
    const std::vector<Eigen::MatrixXcd>& R)
{
    double total = 0;
    for (size_t g = 0; g < groupFreqs.size() && g < R.size(); ++g)
        total += quadraticForm(R[g], array.steeringVector(theta, groupFreqs[g], n));
    return total;
}

double goldenMaximize(const std::function<double(double)>& f, double a, double b, int iterations)
{
    const double r = 0.5 * (std::sqrt(5.0) - 1.0);
    double c = b - r * (b - a), d = a + r * (b - a);
    double fc = f(c), fd = f(d);
    for (int it = 0; it < iterations; ++it)
    {
        if (fc > fd)
        {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = f(c);
        }
        else
        {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = f(d);
        }
    }
    return 0.5 * (a + b);
}

double parabolicOffset(double ym, double y0, double yp)
{
    const double den = ym - 2 * y0 + yp;
    if (!(den < 0)) return 0.0;
    return std::clamp(0.5 * (ym - yp) / den, -0.5, 0.5);
}

std::vector<size_t> findPeaks1D(const Eigen::VectorXd& v, bool circular, size_t maxPeaks)
{
    const size_t n = size_t(v.size());
    std::vector<size_t> peaks;
    for (size_t i = 0; i < n; ++i)
    {
        const bool hasL = circular || i > 0, hasR = circular || i + 1 < n;
        const double l = hasL ? v[Eigen::Index((i + n - 1) % n)] : -INFINITY;
        const double r = hasR ? v[Eigen::Index((i + 1) % n)] : -INFINITY;
        if (v[Eigen::Index(i)] >= l && v[Eigen::Index(i)] > r) peaks.push_back(i);
    }
    std::sort(
        peaks.begin(), peaks.end(),
        [&](size_t a, size_t b) { return v[Eigen::Index(a)] > v[Eigen::Index(b)]; });
    if (peaks.size() > maxPeaks) peaks.resize(maxPeaks);
    if (peaks.empty() && n > 0)
    {
        Eigen::Index best;
        v.maxCoeff(&best);
        peaks.push_back(size_t(best));
    }
    return peaks;
}

double refinePeak1D(const Eigen::VectorXd& v, size_t i, bool circular)
{
    const size_t n = size_t(v.size());
    if (n < 3 || (!circular && (i == 0 || i + 1 == n))) return double(i);
    const auto lg = [&](size_t k) { return std::log(std::max(v[Eigen::Index(k)], 1e-300)); };
    return double(i) + parabolicOffset(lg((i + n - 1) % n), lg(i), lg((i + 1) % n));
}

double bartlettQuality(double power, const std::vector<Eigen::MatrixXcd>& R, size_t n)
{
    double total = 0;
    for (const auto& Rg : R) total += Rg.trace().real();
    return total > 0 ? std::clamp(power / (double(n) * total), 0.0, 1.0) : 0.0;
}

double randomFieldQuality(const AntennaArray& array, size_t n, double frequency_Hz)
{
    // Cached per geometry: the estimators call this for every window.
    static thread_local std::map<std::vector<double>, double> cache;
    std::vector<double> key{double(n), std::round(frequency_Hz / 1e5)};
    for (size_t i = 0; i < n; ++i)
        key.insert(key.end(), {array.elements[i].x, array.elements[i].y});
    if (auto it = cache.find(key); it != cache.end()) return it->second;
    const AntennaArray used = array.firstElements(n);
    const auto [lo, hi] = used.searchInterval();
    constexpr int kDirections = 181, kVectors = 64;
    const double k = 2 * M_PI * frequency_Hz / kSpeedOfLightMps;
    std::vector<std::vector<std::complex<double>>> steer(kDirections);
    for (int d = 0; d < kDirections; ++d)
    {
        const double t = lo + (hi - lo) * d / (kDirections - 1);
        for (size_t i = 0; i < n; ++i)
            steer[size_t(d)].push_back(std::polar(
                1.0, k * (used.elements[i].x * std::cos(t) + used.elements[i].y * std::sin(t))));
    }
    // A fixed pseudo-random sequence (same result on every machine and run).
    uint64_t state = 0x2545F4914F6CDD1DULL;
    const auto uniform = [&]()
    {
        state = state * 6364136223846793005ULL + 1442695040888963407ULL;
        return (double((state >> 11) & ((1ULL << 53) - 1)) + 0.5) / double(1ULL << 53);
    };
    double sum = 0;
    for (int v = 0; v < kVectors; ++v)
    {
        std::vector<std::complex<double>> h(n);
        double norm = 0;
        for (auto& x : h)
        {
            // Box–Muller: i.i.d. complex Gaussian entries (a field from every direction).
            const double r = std::sqrt(-2 * std::log(uniform())), a = 2 * M_PI * uniform();
            x = std::polar(r, a);
            norm += std::norm(x);
        }
        double best = 0;
        for (const auto& a : steer)
        {
            std::complex<double> dot = 0;
            for (size_t i = 0; i < n; ++i) dot += std::conj(a[i]) * h[i];
            best = std::max(best, std::norm(dot));
        }
        sum += best / (double(n) * norm);
    }
    return cache[key] = sum / kVectors;
}

double bearingStd(
    const AntennaArray& array, size_t n, double theta, const std::vector<Eigen::MatrixXcd>& R,
    const std::vector<double>& groupFreqs, const std::vector<double>& groupCounts,
    double snapshotsPerSubcarrier, double quality, double floor_rad)
{
    Eigen::MatrixXcd sum = Eigen::MatrixXcd::Zero(Eigen::Index(n), Eigen::Index(n));
    for (const auto& Rg : R) sum += Rg;
    double snapshots = 0;
    for (double c : groupCounts) snapshots += c * snapshotsPerSubcarrier;
    double snr = 1e-3;
    if (n >= 2 && snapshots > 0)
    {
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> es(sum, Eigen::EigenvaluesOnly);
        const auto& ev = es.eigenvalues();
        const double noise = std::max(ev.head(Eigen::Index(n) - 1).mean() / snapshots, 1e-12);
        const double signal = (ev[Eigen::Index(n) - 1] / snapshots - noise) / double(n);
        snr = std::max(signal / noise, 1e-3);
    }
    double info = 0;
    for (size_t g = 0; g < groupFreqs.size(); ++g)
    {
        const double crb = array.aoaCramerRaoBound(
            theta, {groupFreqs[g]}, snr, groupCounts[g] * snapshotsPerSubcarrier, n);
        if (std::isfinite(crb) && crb > 0) info += 1.0 / (crb * crb);
    }
    const double crb = info > 0 ? 1.0 / std::sqrt(info) : M_PI;
    // Power the plane wave does not explain (1 − q) acts like an interferer inside the beam:
    // its pull on the peak scales with the beamwidth (0.886 λ / aperture) and with the
    // interferer-to-signal amplitude ratio √((1 − q)/q).
    double aperture = 0;
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i + 1; j < n; ++j)
            aperture = std::max(aperture, (array.elements[i] - array.elements[j]).norm());
    double fc = 0;
    for (double f : groupFreqs) fc += f / double(groupFreqs.size());
    const double beamwidth =
        aperture > 0 && fc > 0 ? std::min(0.886 * kSpeedOfLightMps / fc / aperture, M_PI) : M_PI;
    // The share q of the power one plane wave explains overstates a clean path when the
    // window's covariance is (nearly) one spatial signature, as a static transmitter's coherent
    // multipath gives: few antennas fit any single vector well (3 antennas 57.5 mm apart: a
    // random one reaches q = 0.74). There the unexplained power is measured against what a
    // random field leaves, 1 − q_random; with two or more independent signatures (effective
    // rank (tr R)² / ‖R‖² ≥ 2: a moving receiver, a wide band) q stands as it is.
    double q = quality;
    if (n >= 2 && fc > 0)
    {
        const double fro2 = sum.squaredNorm(), tr = sum.trace().real();
        const double rank = fro2 > 0 ? tr * tr / fro2 : double(n);
        const double oneSignature = std::clamp(2.0 - rank, 0.0, 1.0);
        q = 1 - (1 - quality) / (1 - oneSignature * randomFieldQuality(array, n, fc));
    }
    q = std::clamp(q, 0.05, 1.0);
    const double multipath = 0.25 * beamwidth * std::sqrt((1 - q) / q);
    return std::min(std::sqrt(crb * crb + floor_rad * floor_rad + multipath * multipath), M_PI / 2);
}

void sumCovariances(
    const std::vector<const CleanCsi*>& frames, unsigned groups, bool transmitSide,
    std::vector<Eigen::MatrixXcd>& out)
{
    out.resize(groups);
    bool first = true;
    for (const CleanCsi* f : frames)
    {
        const auto& c = transmitSide ? f->txGroupCovariances(groups) : f->groupCovariances(groups);
        for (unsigned g = 0; g < groups; ++g)
        {
            if (first)
                out[g] = c[g];
            else
                out[g] += c[g];
        }
        first = false;
    }
}

unsigned signalDimension(const Eigen::VectorXd& ev, double threshold, unsigned maxPaths)
{
    const Eigen::Index n = ev.size();
    if (n < 2) return 1;
    // Noise level: the smallest eigenvalue's neighbourhood (mean of the lower half, ≥ 1 value).
    const Eigen::Index lower = std::max<Eigen::Index>(1, n / 2);
    const double noise = std::max(ev.head(lower).mean(), 1e-12 * std::max(ev[n - 1], 1e-300));
    unsigned k = 0;
    for (Eigen::Index i = n - 1; i >= 0; --i)
        if (ev[i] > threshold * noise) ++k;
    return std::clamp<unsigned>(k, 1, std::min<unsigned>(maxPaths, unsigned(n - 1)));
}

void noiseProjectors(
    const std::vector<Eigen::MatrixXcd>& R, unsigned signalDim, std::vector<Eigen::MatrixXcd>& out)
{
    out.resize(R.size());
    for (size_t g = 0; g < R.size(); ++g)
    {
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> es(R[g]);
        const Eigen::Index n = R[g].rows();
        const Eigen::Index noiseDim = std::max<Eigen::Index>(n - Eigen::Index(signalDim), 1);
        const auto En = es.eigenvectors().leftCols(noiseDim);
        out[g] = En * En.adjoint();
    }
}

Eigen::MatrixXf quadraticFormBasis(
    const AntennaArray& array, size_t n, const AngleGrid& grid, double frequency_Hz)
{
    Eigen::MatrixXf B(Eigen::Index(grid.size()), Eigen::Index(1 + n * (n - 1)));
    for (size_t t = 0; t < grid.size(); ++t)
    {
        const Eigen::VectorXcd a = array.steeringVector(grid.angles[t], frequency_Hz, n);
        Eigen::Index c = 0;
        B(Eigen::Index(t), c++) = 1.f;
        for (size_t i = 0; i < n; ++i)
            for (size_t j = i + 1; j < n; ++j)
            {
                const std::complex<double> w = std::conj(a[Eigen::Index(i)]) * a[Eigen::Index(j)];
                B(Eigen::Index(t), c++) = float(2 * w.real());
                B(Eigen::Index(t), c++) = float(-2 * w.imag());
            }
    }
    return B;
}

// ---------------------------------------------------------------------------------------------
void TopEigenvectors::compute(const Eigen::MatrixXcd& A)
{
    // As SelfAdjointEigenSolver: entries mapped to [−1, 1] (QR's deflation test assumes it).
    double scale = A.cwiseAbs().maxCoeff();
    if (!(scale > 0)) scale = 1;
    tri_.compute(A / scale);
    sub_ = tri_.subDiagonal();
    es_.computeFromTridiagonal(tri_.diagonal(), sub_, Eigen::EigenvaluesOnly);
    eigenvalues_ = es_.eigenvalues() * scale;
}

const Eigen::MatrixXcd& TopEigenvectors::eigenvectors(Eigen::Index count)
{
    const Eigen::VectorXd d = tri_.diagonal();
    const Eigen::Index n = d.size();
    count = std::clamp<Eigen::Index>(count, 0, n);
    const auto& ev = es_.eigenvalues();  // of T (scaled)
    double normT = 0;                    // ‖T‖_∞
    for (Eigen::Index i = 0; i < n; ++i)
        normT = std::max(
            normT, std::abs(d[i]) + (i > 0 ? std::abs(sub_[i - 1]) : 0.0) +
                       (i + 1 < n ? std::abs(sub_[i]) : 0.0));
    constexpr double eps = std::numeric_limits<double>::epsilon();
    const double tiny = std::max(eps * normT, std::numeric_limits<double>::min());
    const double clusterGap = 1e-3 * normT;  // dstein's ORTOL
    Z_.resize(n, count);
    lu_d_.resize(n);
    lu_dl_.resize(std::max<Eigen::Index>(n - 1, 0));
    lu_du_.resize(std::max<Eigen::Index>(n - 1, 0));
    lu_du2_.resize(std::max<Eigen::Index>(n - 2, 0));
    pivot_.resize(size_t(n));
    double previous = -INFINITY;
    for (Eigen::Index c = 0; c < count; ++c)
    {
        const Eigen::Index k = n - count + c;
        // Equal eigenvalues get slightly different shifts, so their solves differ.
        double lambda = ev[k];
        if (lambda - previous < 10 * eps * std::abs(lambda))
            lambda = previous + 10 * eps * std::abs(lambda);
        previous = lambda;
        // LU with partial pivoting of T − λI (LAPACK dgttrf); a vanishing pivot becomes `tiny`.
        for (Eigen::Index i = 0; i < n; ++i) lu_d_[i] = d[i] - lambda;
        for (Eigen::Index i = 0; i + 1 < n; ++i) lu_dl_[i] = lu_du_[i] = sub_[i];
        for (Eigen::Index i = 0; i + 2 < n; ++i) lu_du2_[i] = 0;
        for (Eigen::Index i = 0; i + 1 < n; ++i)
        {
            if (std::abs(lu_d_[i]) >= std::abs(lu_dl_[i]))
            {
                pivot_[size_t(i)] = 0;
                if (std::abs(lu_d_[i]) < tiny) lu_d_[i] = tiny;
                const double f = lu_dl_[i] / lu_d_[i];
                lu_dl_[i] = f;
                lu_d_[i + 1] -= f * lu_du_[i];
            }
            else
            {
                pivot_[size_t(i)] = 1;  // rows i and i + 1 swapped
                const double f = lu_d_[i] / lu_dl_[i];
                lu_d_[i] = lu_dl_[i];
                lu_dl_[i] = f;
                const double t = lu_du_[i];
                lu_du_[i] = lu_d_[i + 1];
                lu_d_[i + 1] = t - f * lu_d_[i + 1];
                if (i + 2 < n)
                {
                    lu_du2_[i] = lu_du_[i + 1];
                    lu_du_[i + 1] = -f * lu_du_[i + 1];
                }
            }
        }
        if (n > 0 && std::abs(lu_d_[n - 1]) < tiny) lu_d_[n - 1] = tiny;
        // A fixed start with components along every eigenvector (as dstein's random one).
        x_.resize(n);
        for (Eigen::Index i = 0; i < n; ++i) x_[i] = 1.0 + 0.5 * std::sin(double(3 * i + 1));
        for (int iteration = 0; iteration < 3; ++iteration)
        {
            for (Eigen::Index i = 0; i + 1 < n; ++i)  // L
            {
                if (pivot_[size_t(i)]) std::swap(x_[i], x_[i + 1]);
                x_[i + 1] -= lu_dl_[i] * x_[i];
            }
            for (Eigen::Index i = n - 1; i >= 0; --i)  // U
            {
                double v = x_[i];
                if (i + 1 < n) v -= lu_du_[i] * x_[i + 1];
                if (i + 2 < n) v -= lu_du2_[i] * x_[i + 2];
                x_[i] = v / lu_d_[i];
            }
            for (Eigen::Index o = 0; o < c; ++o)  // orthogonal to its cluster's other vectors
                if (std::abs(ev[n - count + o] - ev[k]) <= clusterGap)
                    x_ -= Z_.col(o).dot(x_) * Z_.col(o);
            x_.normalize();
        }
        Z_.col(c) = x_;
    }
    V_ = tri_.matrixQ() * Z_.cast<std::complex<double>>();
    return V_;
}

// ---------------------------------------------------------------------------------------------
void AngleDelayProfile::prepare(
    const AntennaArray& array, size_t nRx, const SubcarrierLayout& layout, const AngleGrid& grid,
    const std::vector<double>& delays_s, unsigned decimation)
{
    nRx_ = nRx;
    decimation = std::max(1u, decimation);
    groups_.clear();
    std::vector<double> meanK;
    for (size_t b = 0; b < layout.size(); b += decimation)
    {
        const size_t e = std::min(layout.size(), b + decimation);
        groups_.emplace_back(Eigen::Index(b), Eigen::Index(e));
        double k = 0;
        for (size_t j = b; j < e; ++j) k += layout.subcarriers[j];
        meanK.push_back(k / double(e - b));
    }
    D_.resize(Eigen::Index(groups_.size()), Eigen::Index(delays_s.size()));
    for (size_t g = 0; g < groups_.size(); ++g)
        for (size_t d = 0; d < delays_s.size(); ++d)
            D_(Eigen::Index(g), Eigen::Index(d)) = std::complex<float>(
                std::polar(1.0, 2 * M_PI * meanK[g] * kSubcarrierSpacingHz * delays_s[d]));
    B_ = quadraticFormBasis(array, nRx, grid, layout.centerFrequency_Hz);
    C_.resize(B_.cols(), Eigen::Index(delays_s.size()));
    cacheOwner_ = CleanCsi::newDerivedOwner();
    reset();
}

void AngleDelayProfile::reset()
{
    Csum_.setZero(B_.cols(), D_.cols());
    powerValid_ = false;
}

void AngleDelayProfile::accumulate(const Eigen::MatrixXcf& H, unsigned nStreams)
{
    terms(H, nStreams, C_);
    Csum_ += C_;
    powerValid_ = false;
}

void AngleDelayProfile::accumulate(const CleanCsi& frame)
{
    Csum_ += frame.derived<Eigen::MatrixXf>(
        cacheOwner_, [&](Eigen::MatrixXf& C) { terms(frame.H, frame.nTx, C); });
    powerValid_ = false;
}

const Eigen::MatrixXf& AngleDelayProfile::power()
{
    if (!powerValid_)
    {
        P_.noalias() = B_ * Csum_;
        powerValid_ = true;
    }
    return P_;
}

void AngleDelayProfile::terms(const Eigen::MatrixXcf& H, unsigned nStreams, Eigen::MatrixXf& C)
{
    C.resize(B_.cols(), D_.cols());
    Hd_.resize(H.rows(), Eigen::Index(groups_.size()));
    for (size_t g = 0; g < groups_.size(); ++g)
    {
        const auto [b, e] = groups_[g];
        Hd_.col(Eigen::Index(g)) = H.middleCols(b, e - b).rowwise().sum();
    }
    Y_.noalias() = Hd_ * D_;  // (streams·rx) × delays
    const Eigen::Index n = Eigen::Index(nRx_);
    C.setZero();
    for (Eigen::Index d = 0; d < Y_.cols(); ++d)
    {
        const std::complex<float>* y = Y_.data() + d * Y_.rows();
        for (unsigned m = 0; m < nStreams; ++m) addOuterProductCoefficients(y + m * n, n, &C(0, d));
    }
}

Peak2D refinePeak2D(const Eigen::MatrixXf& P, size_t i, size_t j, bool circularRows)
{
    Peak2D p;
    p.i = i;
    p.j = j;
    p.fi = double(i);
    p.fj = double(j);
    p.value = P(Eigen::Index(i), Eigen::Index(j));
    const size_t nr = size_t(P.rows()), nc = size_t(P.cols());
    const auto lg = [&](size_t r, size_t c)
    { return std::log(std::max<double>(P(Eigen::Index(r), Eigen::Index(c)), 1e-30)); };
    if (nr >= 3 && (circularRows || (i > 0 && i + 1 < nr)))
        p.fi += parabolicOffset(lg((i + nr - 1) % nr, j), lg(i, j), lg((i + 1) % nr, j));
    if (nc >= 3 && j > 0 && j + 1 < nc)
        p.fj += parabolicOffset(lg(i, j - 1), lg(i, j), lg(i, j + 1));
    return p;
}

std::vector<Peak2D> findPeaks2D(const Eigen::MatrixXf& P, bool circularRows, size_t maxPeaks)
{
    const long nr = long(P.rows()), nc = long(P.cols());
    // True if (i, j) is a local maximum of its 8-neighbourhood. Ties: the first in row-major
    // scan order wins, so plateaus give one peak.
    const auto isMax = [&](long i, long j, float v)
    {
        for (long di = -1; di <= 1; ++di)
            for (long dj = -1; dj <= 1; ++dj)
            {
                if (!di && !dj) continue;
                long ii = i + di;
                const long jj = j + dj;
                if (jj < 0 || jj >= nc) continue;
                if (ii < 0 || ii >= nr)
                {
                    if (!circularRows) continue;
                    ii = (ii + nr) % nr;
                }
                const float w = P(ii, jj);
                if (w > v || (w == v && (ii < i || (ii == i && jj < j)))) return false;
            }
        return true;
    };
    std::vector<Peak2D> peaks;
    for (long j = 0; j < nc; ++j)
    {
        const float* col = P.data() + j * nr;  // contiguous along the angle axis
        for (long i = 0; i < nr; ++i)
        {
            const float v = col[i];
            // Most cells have a strictly larger neighbour in their own column: rejected first.
            if ((i > 0 && col[i - 1] > v) || (i + 1 < nr && col[i + 1] > v)) continue;
            if (!isMax(i, j, v)) continue;
            Peak2D p;
            p.i = size_t(i);
            p.j = size_t(j);
            p.value = v;
            peaks.push_back(p);
        }
    }
    // Row-major order first, then by value: equal peaks keep the order of a row-major scan.
    std::sort(
        peaks.begin(), peaks.end(),
        [](const Peak2D& a, const Peak2D& b) { return std::tie(a.i, a.j) < std::tie(b.i, b.j); });
    std::sort(
        peaks.begin(), peaks.end(),
        [](const Peak2D& a, const Peak2D& b) { return a.value > b.value; });
    if (peaks.size() > maxPeaks) peaks.resize(maxPeaks);
    return peaks;
}

void delayFilteredCovariances(
    const std::vector<const CleanCsi*>& frames, double delay_s, unsigned groups,
    std::vector<Eigen::MatrixXcd>& R)
{
    if (frames.empty()) return;
    const CleanCsi& f0 = *frames.front();
    const auto& k = f0.layout->subcarriers;
    const Eigen::Index nSub = Eigen::Index(k.size());
    Eigen::VectorXcf d(nSub);
    for (Eigen::Index j = 0; j < nSub; ++j)
        d[j] = std::complex<float>(
            std::polar(1.0, 2 * M_PI * k[size_t(j)] * kSubcarrierSpacingHz * delay_s));
    R.assign(groups, Eigen::MatrixXcd::Zero(f0.nRx, f0.nRx));
    for (const CleanCsi* f : frames)
        for (unsigned g = 0; g < groups; ++g)
        {
            const auto [b, e] = CleanCsi::groupRange(size_t(nSub), groups, g);
            const Eigen::VectorXcf yAll = f->H.middleCols(Eigen::Index(b), Eigen::Index(e - b)) *
                                          d.segment(Eigen::Index(b), Eigen::Index(e - b));
            for (unsigned m = 0; m < f->nTx; ++m)
            {
                const Eigen::VectorXcd y =
                    yAll.segment(Eigen::Index(m * f->nRx), f->nRx).cast<std::complex<double>>();
                R[g] += y * y.adjoint();
            }
        }
}

namespace
{
// alternativeWeight()'s logistic model, fitted by scripts/alternative_weights.py on
// `bearing-accuracy --rooms 60 --stream --development --snr 25 --algo default --algo aoa_only
// --algo music` (243,416 candidates of 100,980 bearings, 4,774 of them right).
constexpr double kAltIntercept = -2.045, kAltLogPower = 3.04, kAltUnexplained = 2.055,
                 kAltHasDelay = -3.795, kAltDelay = -0.4724, kAltDelayLogPower = -2.252,
                 kAltDelayUnexplained = 4.814;
}  // namespace

double alternativeWeight(double relativePower, double delayAfter_s, double quality)
{
    // Coefficients fitted by scripts/alternative_weights.py (logistic regression) on the
    // development rooms; see docs/evaluation.md for the command and the fit's table.
    const double logRho = std::log(std::clamp(relativePower, 1e-3, 1e3));
    const double unexplained = std::clamp(1 - quality, 0.0, 1.0);
    const bool hasDelay = std::isfinite(delayAfter_s);
    const double later_ns = hasDelay ? std::clamp(delayAfter_s * 1e9, -50.0, 50.0) : 0.0;
    const double z = kAltIntercept + kAltLogPower * logRho + kAltUnexplained * unexplained +
                     (hasDelay ? kAltHasDelay + kAltDelay * later_ns + kAltDelayLogPower * logRho +
                                     kAltDelayUnexplained * unexplained
                               : 0.0);
    return 1 / (1 + std::exp(-z));
}

}  // namespace mrpt_wifi::bearing::detail
