/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include "BearingMath.h"

#include <mrpt_wifi/obs/Subcarriers.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>

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
    const double q = std::clamp(quality, 0.05, 1.0);
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
    const size_t nb = 1 + nRx * (nRx - 1);
    B_.resize(Eigen::Index(grid.size()), Eigen::Index(nb));
    for (size_t t = 0; t < grid.size(); ++t)
    {
        const Eigen::VectorXcd a =
            array.steeringVector(grid.angles[t], layout.centerFrequency_Hz, nRx);
        Eigen::Index c = 0;
        B_(Eigen::Index(t), c++) = 1.f;
        for (size_t i = 0; i < nRx; ++i)
            for (size_t j = i + 1; j < nRx; ++j)
            {
                const std::complex<double> w = std::conj(a[Eigen::Index(i)]) * a[Eigen::Index(j)];
                B_(Eigen::Index(t), c++) = float(2 * w.real());
                B_(Eigen::Index(t), c++) = float(-2 * w.imag());
            }
    }
    C_.resize(Eigen::Index(nb), Eigen::Index(delays_s.size()));
    P_.setZero(B_.rows(), D_.cols());
}

void AngleDelayProfile::reset()
{
    P_.setZero(B_.rows(), D_.cols());
}

void AngleDelayProfile::accumulate(const Eigen::MatrixXcf& H, unsigned nStreams)
{
    Hd_.resize(H.rows(), Eigen::Index(groups_.size()));
    for (size_t g = 0; g < groups_.size(); ++g)
    {
        const auto [b, e] = groups_[g];
        Hd_.col(Eigen::Index(g)) = H.middleCols(b, e - b).rowwise().sum();
    }
    Y_.noalias() = Hd_ * D_;  // (streams·rx) × delays
    const Eigen::Index n = Eigen::Index(nRx_);
    for (Eigen::Index d = 0; d < Y_.cols(); ++d)
    {
        const std::complex<float>* y = Y_.data() + d * Y_.rows();
        float trace = 0;
        float cross[2 * 28] = {};  // up to 8 antennas: 28 pairs
        for (unsigned m = 0; m < nStreams; ++m)
        {
            const std::complex<float>* v = y + m * n;
            Eigen::Index c = 0;
            for (Eigen::Index i = 0; i < n; ++i)
            {
                trace += std::norm(v[i]);
                for (Eigen::Index j = i + 1; j < n; ++j, c += 2)
                {
                    // R_ij = v_i · conj(v_j)
                    cross[c] += v[i].real() * v[j].real() + v[i].imag() * v[j].imag();
                    cross[c + 1] += v[i].imag() * v[j].real() - v[i].real() * v[j].imag();
                }
            }
        }
        C_(0, d) = trace;
        for (Eigen::Index c = 0; c + 1 < C_.rows(); ++c) C_(c + 1, d) = cross[c];
    }
    P_.noalias() += B_ * C_;
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
    std::vector<Peak2D> peaks;
    for (long i = 0; i < nr; ++i)
        for (long j = 0; j < nc; ++j)
        {
            const float v = P(i, j);
            bool isMax = true;
            for (long di = -1; di <= 1 && isMax; ++di)
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
                    // Ties: the first in scan order wins, so plateaus give one peak.
                    if (w > v || (w == v && (ii < i || (ii == i && jj < j))))
                    {
                        isMax = false;
                        break;
                    }
                }
            if (isMax)
            {
                Peak2D p;
                p.i = size_t(i);
                p.j = size_t(j);
                p.value = v;
                peaks.push_back(p);
            }
        }
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

}  // namespace mrpt_wifi::bearing::detail
