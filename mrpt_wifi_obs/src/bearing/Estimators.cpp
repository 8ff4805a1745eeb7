/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * The seven bearing estimators. All share one pipeline shape: per-frame statistics computed once
 * (CleanCsi caches its covariances), summed over the window, then a grid search on precomputed
 * steering data and a grid-free polish of the chosen peak. Steering uses each sub-band's own
 * centre frequency (frequency_groups) where the cost allows; the 2-D angle × delay searches use
 * the band centre (the band-edge phase error is ≤ 3.6° on a 78 mm baseline and zero-mean across
 * the symmetric band) and their bearing is then polished with the grouped wideband model. */
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/obs/bearing/BearingEstimator.h>
#include <mrpt_wifi/obs/bearing/SyntheticAperture.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

#include "BearingMath.h"

namespace mrpt_wifi::bearing
{
using namespace detail;

namespace
{
const std::vector<std::string> kCommon1D = {"angle_bins", "window",        "frequency_groups",
                                            "refine",     "std_floor_deg", "keep_profile"};
std::vector<std::string> plus(std::vector<std::string> a, const std::vector<std::string>& b)
{
    a.insert(a.end(), b.begin(), b.end());
    return a;
}
const std::vector<std::string> kDelayKeys = {"delay_bins", "delay_min_ns", "delay_max_ns"};
const std::vector<std::string> kProfileKeys = {
    "delay_bins", "delay_min_ns", "delay_max_ns", "delay_decimation"};
const std::vector<std::string> kSubspaceKeys = {"max_paths", "subspace_threshold"};

/** A linear array's bearing as its candidate in the front half-plane (others: wrapped). */
double frontHalfPlane(const AntennaArray& used, double theta)
{
    const bool linear = used.size() >= 2 && used.isLinear();
    theta = wrapAngle(theta);
    return linear && angleDistance(theta, used.broadside()) > M_PI / 2 ? used.mirrorOf(theta)
                                                                       : theta;
}

/** Stores a bearing (any angle) as the front-half-plane candidate plus its mirror, with no
 *  alternative (its direction's σ the same). */
void setAoa(BearingResult& r, const AntennaArray& used, double theta, double std_rad)
{
    const bool linear = used.size() >= 2 && used.isLinear();
    theta = frontHalfPlane(used, theta);
    r.aoa_rad = theta;
    r.aoaStd_rad = std_rad;
    r.aoaDirectionStd_rad = std_rad;
    r.hasAoaAlternative = false;
    r.aoaAmbiguous = linear;
    r.aoaMirror_rad = linear ? used.mirrorOf(theta) : theta;
}

void setAod(BearingResult& r, const AntennaArray& used, double theta, double std_rad)
{
    const bool linear = used.size() >= 2 && used.isLinear();
    theta = wrapAngle(theta);
    if (linear && angleDistance(theta, used.broadside()) > M_PI / 2) theta = used.mirrorOf(theta);
    r.hasAod = true;
    r.aod_rad = theta;
    r.aodStd_rad = std_rad;
    r.aodAmbiguous = linear;
    r.aodMirror_rad = linear ? used.mirrorOf(theta) : theta;
}

std::vector<double> delayGrid(const EstimatorOptions& o)
{
    std::vector<double> d(o.delayBins);
    for (unsigned i = 0; i < o.delayBins; ++i)
        d[i] = 1e-9 * (o.delayMin_ns + (o.delayMax_ns - o.delayMin_ns) * i / (o.delayBins - 1));
    return d;
}

double delayAt(const std::vector<double>& d, double fj)
{
    if (d.size() < 2) return d.empty() ? 0.0 : d[0];
    return d[0] + (d[1] - d[0]) * fj;
}

/** Common machinery: receive-side grid, sub-band frequencies, quadratic-form tables, all
 *  rebuilt only when the array, channel layout, antenna count or options change. */
class EstimatorBase : public BearingEstimator
{
protected:
    /** Returns false if the frames can't be used (no frames, one antenna). */
    bool prepare(const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx)
    {
        if (frames.empty() || !ctx.rxArray) return false;
        const CleanCsi& f = *frames.back();
        if (f.nRx < 2 || f.nRx > ctx.rxArray->size()) return false;
        const auto key = std::make_tuple(
            f.layout.get(), f.nRx, ctx.rxArray, opts_.angleBins, opts_.frequencyGroups,
            opts_.delayBins, opts_.delayMin_ns, opts_.delayMax_ns,
            opts_.subcarrierStep * 1000 + opts_.delayDecimation, opts_.smoothingLength);
        if (prepared_ && key == key_) return true;
        key_ = key;
        rx_ = ctx.rxArray->firstElements(f.nRx);
        grid_ = AngleGrid::make(rx_, f.nRx, opts_.angleBins);
        groupFrequencies(*f.layout, opts_.frequencyGroups, gf_, gc_);
        qf_.prepare(rx_, f.nRx, grid_, gf_);
        layout_ = f.layout;
        onPrepare(f);
        prepared_ = true;
        return true;
    }
    virtual void onPrepare(const CleanCsi&) {}

    static double snapshotsPerSubcarrier(const std::vector<const CleanCsi*>& frames)
    {
        double s = 0;
        for (const auto* f : frames) s += f->nTx;
        return s;
    }

    /** Grid-free polish of a bearing: successive parabolas through f(θ−h), f(θ), f(θ+h) with
     *  h shrinking 4× per round, f = Σ_g a_g^H R_g a_g (wideband, sub-band wavelengths). */
    double polishBartlett(double theta, const std::vector<Eigen::MatrixXcd>& R) const
    {
        return polish(theta, [&](double t) { return fastGroupedForm(t, R); });
    }

    double polish(double theta, const std::function<double(double)>& f) const
    {
        double h = 0.5 * grid_.step;
        for (int round = 0; round < 4; ++round, h *= 0.25)
        {
            const double fm = f(theta - h), f0 = f(theta), fp = f(theta + h);
            if (fm > f0 && fm >= fp)
                theta -= h;  // still climbing: step towards the larger side
            else if (fp > f0)
                theta += h;
            else
                theta += h * parabolicOffset(fm, f0, fp);
        }
        return theta;
    }

    /** Σ_g a_g(θ)^H R_g a_g(θ) without allocating (element projections computed once). */
    double fastGroupedForm(double theta, const std::vector<Eigen::MatrixXcd>& R) const
    {
        const size_t n = rx_.size();
        double proj[CObservationWiFiCSI::kMaxChains];
        const double c = std::cos(theta), s = std::sin(theta);
        for (size_t i = 0; i < n; ++i) proj[i] = rx_.elements[i].x * c + rx_.elements[i].y * s;
        double total = 0;
        std::complex<double> a[CObservationWiFiCSI::kMaxChains];
        for (size_t g = 0; g < gf_.size() && g < R.size(); ++g)
        {
            const double k = 2 * M_PI * gf_[g] / kSpeedOfLightMps;
            for (size_t i = 0; i < n; ++i) a[i] = std::polar(1.0, k * proj[i]);
            const auto& Rg = R[g];
            for (size_t i = 0; i < n; ++i)
            {
                total += Rg(Eigen::Index(i), Eigen::Index(i)).real();
                for (size_t j = i + 1; j < n; ++j)
                    total +=
                        2 * (std::conj(a[i]) * Rg(Eigen::Index(i), Eigen::Index(j)) * a[j]).real();
            }
        }
        return total;
    }

    /** Quality, σ, the mirror pair and the weighted alternatives of a bearing; `ambiguityR`:
     *  the covariance whose other directions count as ambiguity (default: R); `paths`: the
     *  other paths of an angle × delay profile (relative power and delay after the chosen
     *  one), candidates besides the Bartlett spectrum's peaks. */
    void finish(
        BearingResult& r, double theta, const std::vector<Eigen::MatrixXcd>& R,
        const std::vector<const CleanCsi*>& frames,
        const std::vector<Eigen::MatrixXcd>* ambiguityR = nullptr,
        const std::vector<AoaAlternative>* paths = nullptr)
    {
        const size_t n = rx_.size();
        const double power = fastGroupedForm(theta, R);
        r.quality = bartlettQuality(power, R, n);
        const double sd = bearingStd(
            rx_, n, theta, R, gf_, gc_, snapshotsPerSubcarrier(frames), r.quality,
            opts_.stdFloor_deg * M_PI / 180);
        std::vector<AoaAlternative> peaks;
        double sigmaReaches = NAN;
        const double amb =
            ambiguityStd(theta, ambiguityR ? *ambiguityR : R, r.quality, &peaks, &sigmaReaches);
        setAoa(r, rx_, theta, std::min(std::sqrt(sd * sd + amb * amb), M_PI / 2));
        r.aoaDirectionStd_rad = std::min(sd, r.aoaStd_rad);
        if (paths) peaks.insert(peaks.begin(), paths->begin(), paths->end());
        weighAlternatives(r, peaks, sigmaReaches);
        r.framesUsed = unsigned(frames.size());
        r.valid = true;
    }

    /** The directions other than r.aoa_rad a beamwidth or more from it and from each other
     *  (the profile's paths first, then the Bartlett peaks), each weighed by the measured model
     *  (alternativeWeight); those of weight ≥ kMinAlternativeWeight or stronger than r.aoa_rad,
     *  heaviest first, at most kMaxAoaAlternatives, become r's alternatives, and always the one
     *  at `sigmaReaches` (the direction aoaStd_rad reaches: a consumer of the mixture, which
     *  takes each direction's own σ, must still see it). All of them stay in r.aoaCandidates. */
    void weighAlternatives(
        BearingResult& r, const std::vector<AoaAlternative>& found, double sigmaReaches = NAN) const
    {
        const double beam = beamwidth();
        r.aoaCandidates.clear();
        for (const auto& c : found)
        {
            if (!std::isfinite(c.aoa_rad) || !(c.relativePower > 0)) continue;
            if (foldedDistance(c.aoa_rad, r.aoa_rad) < beam) continue;
            bool near = false;
            for (const auto& k : r.aoaCandidates)
                near = near || foldedDistance(c.aoa_rad, k.aoa_rad) < beam;
            if (near) continue;
            AoaAlternative a = c;
            a.aoa_rad = frontHalfPlane(rx_, c.aoa_rad);
            a.weight = alternativeWeight(a.relativePower, a.delayAfter_s, r.quality);
            r.aoaCandidates.push_back(a);
        }
        std::vector<AoaAlternative> kept;
        for (auto a : r.aoaCandidates)
            if (a.weight >= kMinAlternativeWeight || a.relativePower >= 1 ||
                (std::isfinite(sigmaReaches) && foldedDistance(a.aoa_rad, sigmaReaches) < beam))
            {
                a.weight = std::max(a.weight, kAlternativeWeightFloor);
                kept.push_back(a);
            }
        std::sort(
            kept.begin(), kept.end(),
            [](const auto& a, const auto& b) { return a.weight > b.weight; });
        if (kept.size() > kMaxAoaAlternatives) kept.resize(kMaxAoaAlternatives);
        // The weights are each direction's own odds; together they leave aoa_rad at least
        // 1 − kMaxAlternativesShare.
        double sum = 0;
        for (const auto& a : kept) sum += a.weight;
        if (sum > kMaxAlternativesShare)
            for (auto& a : kept) a.weight *= kMaxAlternativesShare / sum;
        r.setAoaAlternatives(kept);
    }

    /** The paths of an angle × delay profile other than `chosen`, as candidate alternatives:
     *  power over the chosen one's, delay after it (Candidate: theta, delay, power). */
    template <typename Candidate>
    static std::vector<AoaAlternative> otherPaths(
        const std::vector<Candidate>& cands, const Candidate& chosen)
    {
        std::vector<AoaAlternative> out;
        if (!(chosen.power > 0)) return out;
        for (const auto& c : cands)
        {
            if (c.theta == chosen.theta && c.delay == chosen.delay) continue;
            AoaAlternative a;
            a.aoa_rad = c.theta;
            a.relativePower = c.power / chosen.power;
            a.delayAfter_s = c.delay - chosen.delay;
            out.push_back(a);
        }
        return out;
    }

    /** Distance between two bearings, up to the mirror of a linear array. */
    double foldedDistance(double a, double b) const { return foldedDistanceOn(rx_, grid_, a, b); }
    static double foldedDistanceOn(
        const AntennaArray& array, const AngleGrid& grid, double a, double b)
    {
        const double d = angleDistance(a, b);
        return grid.circular ? d : std::min(d, angleDistance(array.mirrorOf(a), b));
    }

    /** How far the window's CSI also supports other directions: every local maximum of the
     *  wideband Bartlett spectrum (the grid's ends included, so the other endfire, where the
     *  rt-ac86u's 26 mm spacing aliases, counts) at least a beamwidth from the chosen bearing
     *  is a candidate. Power the chosen plane wave leaves unexplained (1 − quality) can move
     *  the two peaks' powers by about 2√(1 − q) of the total, so a candidate with relative power
     *  ρ is ambiguous by w = clamp(1 − (1 − ρ) / (kMargin · 2√(1 − q)), 0, 1) and adds a σ of
     *  kAmbiguityScale · distance · w: a frame with two comparable candidates says so with a σ
     *  that reaches the other one instead of a confident value that may be the wrong one, and
     *  a clean path stays sharp. Constants chosen on the development rooms only. */
    /** `peaks`, when given, receives every such local maximum (its power over theta's), and
     *  `sigmaReaches` the one that set the σ (unchanged when none did). */
    double ambiguityStd(
        double theta, const std::vector<Eigen::MatrixXcd>& R, double quality,
        std::vector<AoaAlternative>* peaks = nullptr, double* sigmaReaches = nullptr)
    {
        return ambiguityStdOn(
            rx_, grid_, qf_, fastGroupedForm(theta, R), theta, R, quality, ambSpec_, peaks,
            sigmaReaches);
    }
    /** The same on any array (the transmitter's for AoD): `powerAtTheta` is the grouped
     *  Bartlett power of `theta` on `R`, `spectrum` scratch space for qf's scan. */
    double ambiguityStdOn(
        const AntennaArray& array, const AngleGrid& grid, QuadraticFormGrid& qf,
        double powerAtTheta, double theta, const std::vector<Eigen::MatrixXcd>& R, double quality,
        Eigen::VectorXd& spectrum, std::vector<AoaAlternative>* peaks = nullptr,
        double* sigmaReaches = nullptr) const
    {
        constexpr double kMargin = 0.5, kAmbiguityScale = 0.5;
        qf.evaluate(R, spectrum);
        const double pMax = std::max(spectrum.maxCoeff(), powerAtTheta);
        if (!(pMax > 0)) return 0;
        const double beam = beamwidthOf(array);
        const double spread =
            std::max(kMargin * 2 * std::sqrt(std::clamp(1 - quality, 0.0, 1.0)), 1e-3);
        double sigma = 0;
        for (size_t i : findPeaks1D(spectrum, grid.circular, 6))
        {
            const double d = foldedDistanceOn(array, grid, theta, grid.angles[i]);
            if (d < beam) continue;
            const double rho = spectrum[Eigen::Index(i)] / pMax;
            const double w = std::clamp(1 - (1 - rho) / spread, 0.0, 1.0);
            const bool setsSigma = kAmbiguityScale * d * w > sigma;
            sigma = std::max(sigma, kAmbiguityScale * d * w);
            if (peaks && powerAtTheta > 0)
            {
                AoaAlternative a;
                a.aoa_rad = grid.at(refinePeak1D(spectrum, i, grid.circular));
                a.relativePower = spectrum[Eigen::Index(i)] / powerAtTheta;
                peaks->push_back(a);
                if (setsSigma && sigmaReaches) *sigmaReaches = a.aoa_rad;
            }
        }
        return sigma;
    }

    /** Half-power beamwidth of the receive array at the band centre [rad]. */
    double beamwidth() const { return beamwidthOf(rx_); }
    double beamwidthOf(const AntennaArray& array) const
    {
        double aperture = 0;
        for (size_t i = 0; i < array.size(); ++i)
            for (size_t j = i + 1; j < array.size(); ++j)
                aperture = std::max(aperture, (array.elements[i] - array.elements[j]).norm());
        const double fc = layout_ ? layout_->centerFrequency_Hz : 5.5e9;
        return aperture > 0 ? std::min(0.886 * kSpeedOfLightMps / fc / aperture, M_PI) : M_PI;
    }

    /** AoD: the transmitter's streams leave from its array elements, so the covariance across
     *  streams (over receive antennas and subcarriers) is a transmit-side spatial covariance,
     *  scanned with the transmitter's array geometry (Bartlett or MUSIC, `aod_method`). Leaves
     *  `r` without AoD when the transmitter's array is unknown or it sent a single stream. */
    void estimateAod(
        const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx, BearingResult& r)
    {
        const CleanCsi& f = *frames.back();
        const AntennaArray* txArray = ctx.txArrayOf ? ctx.txArrayOf(f.transmitter) : nullptr;
        if (!txArray || f.nTx < 2) return;
        for (uint8_t s : f.streamIndex)
            if (s >= txArray->size())
                throw std::invalid_argument(
                    "aod: transmitter " + f.transmitter.asString() + " sends stream " +
                    std::to_string(s) + " but its array '" + txArray->name + "' has " +
                    std::to_string(txArray->size()) + " elements");
        const auto txKey = std::make_tuple(txArray, f.streamIndex, f.layout.get());
        if (!(txPrepared_ && txKey == txKey_))
        {
            tx_ = AntennaArray();
            tx_.name = txArray->name;
            for (uint8_t s : f.streamIndex) tx_.elements.push_back(txArray->elements[s]);
            txGrid_ = AngleGrid::make(tx_, tx_.size(), opts_.angleBins);
            txQf_.prepare(tx_, tx_.size(), txGrid_, gf_);
            txKey_ = txKey;
            txPrepared_ = true;
        }
        sumCovariances(frames, opts_.frequencyGroups, true, Rt_);
        const size_t nT = tx_.size();
        double aod;
        if (opts_.aodMethod == "music")
        {
            Eigen::MatrixXcd total = Rt_[0];
            for (size_t g = 1; g < Rt_.size(); ++g) total += Rt_[g];
            Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> es(total, Eigen::EigenvaluesOnly);
            const unsigned K =
                signalDimension(es.eigenvalues(), opts_.subspaceThreshold, opts_.maxPaths);
            noiseProjectors(Rt_, K, Pt_);
            txQf_.evaluate(Pt_, txSpec_);
            txSpec_ = txSpec_.cwiseMax(1e-12).cwiseInverse();
            double bestPower = -1;
            aod = 0;
            for (size_t p : findPeaks1D(txSpec_, txGrid_.circular, K))
            {
                double t = txGrid_.at(refinePeak1D(txSpec_, p, txGrid_.circular));
                if (opts_.refine)
                    t = goldenMaximize(
                        [&](double x) { return -groupedForm(tx_, nT, x, gf_, Pt_); },
                        t - txGrid_.step, t + txGrid_.step, 28);
                const double power = groupedForm(tx_, nT, t, gf_, Rt_);
                if (power > bestPower)
                {
                    bestPower = power;
                    aod = t;
                }
            }
        }
        else
        {
            txQf_.evaluate(Rt_, txSpec_);
            Eigen::Index b;
            txSpec_.maxCoeff(&b);
            aod = txGrid_.at(refinePeak1D(txSpec_, size_t(b), txGrid_.circular));
            if (opts_.refine)
                aod = goldenMaximize(
                    [&](double x) { return groupedForm(tx_, nT, x, gf_, Rt_); }, aod - txGrid_.step,
                    aod + txGrid_.step, 28);
        }
        const double power = groupedForm(tx_, nT, aod, gf_, Rt_);
        const double q = bartlettQuality(power, Rt_, nT);
        double rxSnapshots = 0;
        for (const auto* fr : frames) rxSnapshots += fr->nRx;
        const double sd = bearingStd(
            tx_, nT, aod, Rt_, gf_, gc_, rxSnapshots, q, opts_.stdFloor_deg * M_PI / 180);
        // As AoA's σ, widened by what the same CSI also supports: near endfire a 4 × 26 mm
        // AP line aliases the other endfire, and a confident wrong AoD pulls every pose.
        const double amb = ambiguityStdOn(tx_, txGrid_, txQf_, power, aod, Rt_, q, txSpec_);
        setAod(r, tx_, aod, std::min(std::hypot(sd, amb), M_PI / 2));
    }

    void keep1D(const Eigen::VectorXd& spectrum, const std::string& label, double peak)
    {
        hasProfile_ = opts_.keepProfile;
        if (!hasProfile_) return;
        profile_.angles_rad = grid_.angles;
        profile_.delays_s = {0.0};
        profile_.values = spectrum.cast<float>();
        profile_.label = label;
        profile_.peakAngle_rad = peak;
        profile_.peakDelay_s = 0;
        profile_.hasPeak = true;
    }

    bool prepared_ = false;
    std::tuple<
        const SubcarrierLayout*, unsigned, const AntennaArray*, unsigned, unsigned, unsigned,
        double, double, unsigned, unsigned>
        key_;
    AntennaArray rx_;
    AngleGrid grid_;
    std::vector<double> gf_, gc_;
    QuadraticFormGrid qf_;
    std::shared_ptr<const SubcarrierLayout> layout_;
    std::vector<Eigen::MatrixXcd> R_, Rd_;
    Eigen::VectorXd spec_, ambSpec_;
    bool txPrepared_ = false;
    std::tuple<const AntennaArray*, std::vector<uint8_t>, const SubcarrierLayout*> txKey_;
    AntennaArray tx_;
    AngleGrid txGrid_;
    QuadraticFormGrid txQf_;
    std::vector<Eigen::MatrixXcd> Rt_, Pt_;
    Eigen::VectorXd txSpec_;
};

// =============================================================================================
/** (1) Fast AoA: Bartlett beam scan of the windowed spatial covariance (WiROS aoa_only), each
 *  sub-band with its own wavelength, then a golden-section polish. */
class AoaOnlyEstimator : public EstimatorBase
{
public:
    std::string name() const override { return "aoa_only"; }
    std::string description() const override
    {
        return "fast AoA: Bartlett scan of the windowed spatial covariance (WiROS aoa_only)";
    }
    std::vector<std::string> parameterKeys() const override { return kCommon1D; }

    bool estimate(
        const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx,
        BearingResult& r) override
    {
        r = BearingResult();
        if (!prepare(frames, ctx)) return false;
        sumCovariances(frames, opts_.frequencyGroups, false, R_);
        qf_.evaluate(R_, spec_);
        Eigen::Index best;
        spec_.maxCoeff(&best);
        double theta = grid_.at(refinePeak1D(spec_, size_t(best), grid_.circular));
        if (opts_.refine) theta = polishBartlett(theta, R_);
        finish(r, theta, R_, frames);
        r.pathsDetected = 1;
        keep1D(spec_, "Bartlett power (AoA)", theta);
        return true;
    }
};

// =============================================================================================
/** (2) 2-D bearing × delay matched-filter profile (WiROS fft), parabolic sub-grid peak, bearing
 *  polished on the covariance of the CSI matched to the peak's delay. */
class ProfileEstimator : public EstimatorBase
{
public:
    std::string name() const override { return "fft"; }
    std::string description() const override
    {
        return "2-D bearing x delay profile (WiROS fft) with sub-grid peak refinement";
    }
    std::vector<std::string> parameterKeys() const override
    {
        return plus(kCommon1D, kProfileKeys);
    }

    bool estimate(
        const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx,
        BearingResult& r) override
    {
        r = BearingResult();
        if (!prepare(frames, ctx)) return false;
        profile2d_.reset();
        for (const auto* f : frames) profile2d_.accumulate(*f);
        double energy = 0;
        for (const auto* f : frames) energy += f->H.squaredNorm();
        return finishProfile(frames, frames, energy, r);
    }

protected:
    void onPrepare(const CleanCsi& f) override
    {
        delays_ = delayGrid(opts_);
        profile2d_.prepare(rx_, f.nRx, *f.layout, grid_, delays_, opts_.delayDecimation);
    }

    /** Picks the strongest cell; `polishFrames` are what the bearing polish uses; with
     *  `followDrift` the estimate follows the window's drift and σ covers it
     *  (followWindowDrift). */
    bool finishProfile(
        const std::vector<const CleanCsi*>& frames,
        const std::vector<const CleanCsi*>& polishFrames, double energy, BearingResult& r,
        bool followDrift = false)
    {
        const Eigen::MatrixXf& P = profile2d_.power();
        Eigen::Index bi, bj;
        P.maxCoeff(&bi, &bj);
        const Peak2D pk = refinePeak2D(P, size_t(bi), size_t(bj), grid_.circular);
        double theta = grid_.at(pk.fi);
        const double delay = delayAt(delays_, pk.fj);
        if (opts_.refine)
        {
            delayFilteredCovariances(polishFrames, delay, opts_.frequencyGroups, Rd_);
            theta = polishBartlett(theta, Rd_);
        }
        const double drift = followDrift ? followWindowDrift(frames, delay, theta) : 0.0;
        sumCovariances(frames, opts_.frequencyGroups, false, R_);
        finish(r, theta, R_, frames);
        widenByDrift(r, drift);
        // Quality from the profile itself: the matched filter's share of the energy.
        const double nSub = double(layout_->size());
        r.quality = std::clamp(double(pk.value) / (double(rx_.size()) * nSub * energy), 0.0, 1.0);
        r.hasDelay = true;
        r.delay_s = delay;
        r.pathsDetected = 1;
        keep2D(P, "Bartlett power", theta, delay);
        return true;
    }

    /** A window's estimate is its frames' mean bearing; while the robot moves, the path's
     *  bearing drifts across the window. The bearing of the path at `delay` in the window's
     *  older and newer half tells how far: a drift below a quarter beamwidth moves `theta` to
     *  the newest frame (half the drift on). Returns the drift [rad] (0 for windows of fewer
     *  than 4 frames), which `widenByDrift` adds to σ. */
    double followWindowDrift(
        const std::vector<const CleanCsi*>& frames, double delay, double& theta)
    {
        if (frames.size() < 4) return 0;
        const size_t h = frames.size() / 2;
        halves_[0].assign(frames.begin(), frames.begin() + long(h));
        halves_[1].assign(frames.end() - long(h), frames.end());
        double half[2];
        for (int k = 0; k < 2; ++k)
        {
            delayFilteredCovariances(halves_[k], delay, opts_.frequencyGroups, Rh_);
            half[k] = polishBartlett(theta, Rh_);
        }
        const double drift = wrapAngle(half[1] - half[0]);
        if (std::abs(drift) < 0.25 * beamwidth()) theta += 0.5 * drift;
        return drift;
    }

    /** σ covers the window's drift (followWindowDrift), in quadrature. */
    static void widenByDrift(BearingResult& r, double drift)
    {
        r.aoaStd_rad = std::min(std::hypot(r.aoaStd_rad, drift), M_PI / 2);
        r.aoaDirectionStd_rad = std::min(std::hypot(r.aoaDirectionStd_rad, drift), M_PI / 2);
    }

    void keep2D(const Eigen::MatrixXf& P, const std::string& label, double theta, double delay)
    {
        hasProfile_ = opts_.keepProfile;
        if (!hasProfile_) return;
        profile_.angles_rad = grid_.angles;
        profile_.delays_s = delays_;
        profile_.values = P;
        profile_.label = label;
        profile_.peakAngle_rad = theta;
        profile_.peakDelay_s = delay;
        profile_.hasPeak = true;
    }

    std::vector<double> delays_;
    AngleDelayProfile profile2d_;
    std::vector<const CleanCsi*> halves_[2];
    std::vector<Eigen::MatrixXcd> Rh_;
};

// =============================================================================================
/** (3) Windowed SVD: the principal components of the window's CSI (one column per frame and
 *  stream) keep what is consistent across frames (the direct path, for a moving robot) and
 *  suppress reflections that change; the components then feed the 2-D profile. */
class SvdEstimator : public ProfileEstimator
{
public:
    SvdEstimator() { opts_.window = 8; }
    std::string name() const override { return "svd"; }
    std::string description() const override
    {
        return "windowed SVD principal-component reflection suppression feeding the 2-D profile";
    }
    std::vector<std::string> parameterKeys() const override
    {
        return plus(plus(kCommon1D, kProfileKeys), {"components"});
    }

    bool estimate(
        const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx,
        BearingResult& r) override
    {
        r = BearingResult();
        if (!prepare(frames, ctx)) return false;
        const CleanCsi& f0 = *frames.back();
        const Eigen::Index nRx = f0.nRx, nSub = f0.H.cols(), rows = nRx * nSub;
        Eigen::Index cols = 0;
        for (const auto* f : frames) cols += f->nTx;
        // Columns: vec(stream block) with the antenna index fastest.
        X_.resize(rows, cols);
        Eigen::Index c = 0;
        for (const auto* f : frames)
            for (unsigned m = 0; m < f->nTx; ++m, ++c)
                Eigen::Map<Eigen::MatrixXcf>(X_.col(c).data(), nRx, nSub) =
                    f->H.middleRows(Eigen::Index(m) * nRx, nRx);
        // Thin SVD through the small Gram matrix (cols ≪ rows). Hermitian: the lower triangle
        // is enough. Column dot products: for this tall, thin shape they are 2.4× faster than
        // Eigen's triangular product, whose packing of the 936-row operand dominates.
        gram_.setZero(cols, cols);
        for (Eigen::Index j = 0; j < cols; ++j)
            for (Eigen::Index i = j; i < cols; ++i)
                gram_(i, j) = std::complex<double>(X_.col(i).dot(X_.col(j)));
        es_.compute(gram_, Eigen::ComputeEigenvectors);  // reads the lower triangle only
        const Eigen::Index keep = std::min<Eigen::Index>(opts_.components, cols);
        pc_.H.resize(keep * nRx, nSub);
        for (Eigen::Index l = 0; l < keep; ++l)
        {
            const Eigen::Index idx = cols - 1 - l;  // eigenvalues ascending
            const Eigen::VectorXcf v = es_.eigenvectors().col(idx).cast<std::complex<float>>();
            // X v = σ u: the component's CSI at its own strength.
            u_.noalias() = X_ * v;
            pc_.H.middleRows(l * nRx, nRx) =
                Eigen::Map<const Eigen::MatrixXcf>(u_.data(), nRx, nSub);
        }
        pc_.nRx = unsigned(nRx);
        pc_.nTx = unsigned(keep);
        pc_.layout = f0.layout;
        profile2d_.reset();
        profile2d_.accumulate(pc_.H, pc_.nTx);
        const std::vector<const CleanCsi*> pcFrames{&pc_};
        // The components average the window: like `default`, follow the path's drift while
        // the robot moves and let σ cover it.
        const bool ok = finishProfile(frames, pcFrames, pc_.H.squaredNorm(), r, true);
        r.pathsDetected = unsigned(keep);
        return ok;
    }

private:
    Eigen::MatrixXcf X_;
    Eigen::VectorXcf u_;
    Eigen::MatrixXcd gram_;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> es_;
    CleanCsi pc_;
};

// =============================================================================================
/** (4) MUSIC over bearing, subcarriers and streams as snapshots (frequency smoothing decorrelates
 *  coherent paths of different delays), one noise subspace per sub-band; the path with the most
 *  Bartlett power among the MUSIC peaks is reported. */
class MusicEstimator : public EstimatorBase
{
public:
    std::string name() const override { return "music"; }
    std::string description() const override
    {
        return "MUSIC over bearing with per-sub-band noise subspaces; strongest path reported";
    }
    std::vector<std::string> parameterKeys() const override
    {
        return plus(kCommon1D, kSubspaceKeys);
    }

    bool estimate(
        const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx,
        BearingResult& r) override
    {
        r = BearingResult();
        if (!prepare(frames, ctx)) return false;
        sumCovariances(frames, opts_.frequencyGroups, false, R_);
        Eigen::MatrixXcd total = R_[0];
        for (size_t g = 1; g < R_.size(); ++g) total += R_[g];
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> es(total, Eigen::EigenvaluesOnly);
        const unsigned K =
            signalDimension(es.eigenvalues(), opts_.subspaceThreshold, opts_.maxPaths);
        noiseProjectors(R_, K, Pn_);
        qf_.evaluate(Pn_, spec_);
        pseudo_ = spec_.cwiseMax(1e-12).cwiseInverse();
        const auto peaks = findPeaks1D(pseudo_, grid_.circular, K);
        double bestTheta = 0, bestPower = -1;
        for (size_t p : peaks)
        {
            double theta = grid_.at(refinePeak1D(pseudo_, p, grid_.circular));
            if (opts_.refine)
                theta = polish(theta, [&](double t) { return -fastGroupedForm(t, Pn_); });
            const double power = fastGroupedForm(theta, R_);
            if (power > bestPower)
            {
                bestPower = power;
                bestTheta = theta;
            }
        }
        finish(r, bestTheta, R_, frames);
        r.pathsDetected = K;
        keep1D(pseudo_, "MUSIC pseudo-spectrum", bestTheta);
        return true;
    }

private:
    std::vector<Eigen::MatrixXcd> Pn_;
    Eigen::VectorXd pseudo_;
};

// =============================================================================================
/** (5) SpotFi: CSI on a decimated uniform subcarrier grid, smoothed over subcarrier shifts
 *  (all antennas × L subcarriers per vector), 2-D MUSIC over bearing × delay; among the peaks
 *  with at least `direct_path_power_ratio` of the strongest one's power, the earliest delay is
 *  the direct path. The window's frames all add to one smoothed covariance. */
class SpotFiEstimator : public ProfileEstimator
{
public:
    SpotFiEstimator()
    {
        opts_.maxPaths = 5;
        opts_.subspaceThreshold = 10;
    }
    std::string name() const override { return "spotfi"; }
    std::string description() const override
    {
        return "SpotFi: smoothed CSI, 2-D MUSIC, direct path = earliest strong delay";
    }
    std::vector<std::string> parameterKeys() const override
    {
        return plus(
            plus(plus(kCommon1D, kDelayKeys), kSubspaceKeys),
            {"subcarrier_step", "smoothing_length", "direct_path_power_ratio"});
    }

    bool estimate(
        const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx,
        BearingResult& r) override
    {
        r = BearingResult();
        if (!prepare(frames, ctx)) return false;
        const Eigen::Index nRx = Eigen::Index(rx_.size()), Ls = Eigen::Index(Ls_);
        const Eigen::Index M = nRx * Ls;
        // Σ over the window of each frame's smoothed covariance (lower triangle), computed
        // once per frame.
        Rs_.setZero(M, M);
        for (const auto* f : frames)
            Rs_ += f->derived<Eigen::MatrixXcf>(
                cacheOwner_, [&](Eigen::MatrixXcf& R) { smoothedCovariance(*f, R); });
        for (Eigen::Index c = 1; c < M; ++c)
            for (Eigen::Index i = 0; i < c; ++i) Rs_(i, c) = std::conj(Rs_(c, i));
        // Eigenvalues, and the eigenvectors of the K strongest only.
        RsD_ = Rs_.cast<std::complex<double>>();
        eig_.compute(RsD_);
        const unsigned K =
            signalDimension(eig_.eigenvalues(), opts_.subspaceThreshold, opts_.maxPaths);
        const Eigen::MatrixXcd& Es = eig_.eigenvectors(Eigen::Index(K));
        // Pseudo-spectrum 1 / (‖s‖² − Σ_j |e_j^H s|²), s = a(θ) ⊗ d(τ), via the Kronecker
        // structure: e_j^H s = a^T · conj(E_j) · d with E_j the eigenvector as nRx × Ls, and
        // |a^T conj(E_j) d|² = |a^H v_j|², v_j = E_j conj(d): per delay a quadratic form in a,
        // so the coefficients of Σ_j v_j v_j^H and one real product with the basis.
        coeffs_.setZero(Bq_.cols(), Eigen::Index(delays_.size()));
        for (unsigned j = 0; j < K; ++j)
        {
            const Eigen::VectorXcf e = Es.col(Eigen::Index(K - 1 - j)).cast<std::complex<float>>();
            for (Eigen::Index i = 0; i < nRx; ++i) Ej_.row(i) = e.segment(i * Ls, Ls).transpose();
            V_.noalias() = Ej_ * DmConj_;
            for (Eigen::Index d = 0; d < V_.cols(); ++d)
                addOuterProductCoefficients(&V_(0, d), nRx, &coeffs_(0, d));
        }
        proj_.noalias() = Bq_ * coeffs_;
        const float norm2 = float(M);
        pseudo_ = (norm2 - proj_.array()).cwiseMax(1e-6f * norm2).inverse().matrix();

        const auto peaks = findPeaks2D(pseudo_, grid_.circular, K);
        std::vector<Candidate>& cands = cands_;
        cands.clear();
        double maxPower = 0;
        for (const auto& p0 : peaks)
        {
            const Peak2D p = refinePeak2D(pseudo_, p0.i, p0.j, grid_.circular);
            const double theta = grid_.at(p.fi), delay = delayAt(delays_, p.fj);
            // Bartlett power of the path on the smoothed covariance.
            const Eigen::VectorXcd a = rx_.steeringVector(theta, layout_->centerFrequency_Hz);
            Eigen::VectorXcd s(M);
            for (Eigen::Index i = 0; i < nRx; ++i)
                for (Eigen::Index l = 0; l < Ls; ++l)
                    s[i * Ls + l] = a[i] * std::polar(
                                               1.0, -2 * M_PI * double(l) * step_ *
                                                        kSubcarrierSpacingHz * delay);
            const double power = (s.adjoint() * RsD_ * s)(0, 0).real();
            cands.push_back({theta, delay, power});
            maxPower = std::max(maxPower, power);
        }
        // Earliest strong peak; peaks within a few ns of it can't be told apart by delay (a
        // grating lobe near endfire, or a path the band can't resolve): the strongest of those.
        constexpr double kSameDelay_s = 5e-9;
        double earliest = INFINITY;
        for (const auto& c : cands)
            if (c.power >= opts_.directPathPowerRatio * maxPower)
                earliest = std::min(earliest, c.delay);
        Candidate chosen{0, 0, -1};
        for (const auto& c : cands)
            if (c.power >= opts_.directPathPowerRatio * maxPower &&
                c.delay <= earliest + kSameDelay_s && c.power > chosen.power)
                chosen = c;
        sumCovariances(frames, opts_.frequencyGroups, false, R_);
        const auto paths = otherPaths(cands, chosen);
        finish(r, chosen.theta, R_, frames, nullptr, &paths);
        r.hasDelay = true;
        r.delay_s = chosen.delay;
        r.pathsDetected = K;
        keep2D(pseudo_, "2-D MUSIC pseudo-spectrum", r.aoa_rad, chosen.delay);
        if (hasProfile_) profile_.peakAngle_rad = chosen.theta;
        return true;
    }

protected:
    /** One frame's smoothed covariance Σ_streams Xs Xs^H (lower triangle; the rest zero). */
    void smoothedCovariance(const CleanCsi& f, Eigen::MatrixXcf& R)
    {
        const Eigen::Index nRx = Eigen::Index(rx_.size()), Ls = Eigen::Index(Ls_);
        const Eigen::Index shifts = Eigen::Index(gridK_.size()) - Ls + 1;
        R.setZero(nRx * Ls, nRx * Ls);
        for (unsigned m = 0; m < f.nTx; ++m)
        {
            // CSI of this stream on the uniform grid (linear interpolation).
            for (Eigen::Index i = 0; i < nRx; ++i)
            {
                const auto row = f.H.row(Eigen::Index(m) * nRx + i);
                for (size_t l = 0; l < gridK_.size(); ++l)
                    U_(i, Eigen::Index(l)) =
                        (1.f - interpT_[l]) * row[interpLo_[l]] + interpT_[l] * row[interpHi_[l]];
            }
            for (Eigen::Index q = 0; q < shifts; ++q)
                for (Eigen::Index i = 0; i < nRx; ++i)
                    Xs_.block(i * Ls, q, Ls, 1) = U_.row(i).segment(q, Ls).transpose();
            R.selfadjointView<Eigen::Lower>().rankUpdate(Xs_);
        }
    }

    void onPrepare(const CleanCsi& f) override
    {
        cacheOwner_ = CleanCsi::newDerivedOwner();
        delays_ = delayGrid(opts_);
        const auto& k = f.layout->subcarriers;
        step_ = opts_.subcarrierStep;
        gridK_.clear();
        interpLo_.clear();
        interpHi_.clear();
        interpT_.clear();
        for (int kk = k.front(); kk <= k.back(); kk += int(step_))
        {
            const auto it = std::lower_bound(k.begin(), k.end(), kk);
            const size_t hi = size_t(it - k.begin());
            const size_t lo = (*it == kk || hi == 0) ? hi : hi - 1;
            gridK_.push_back(kk);
            interpLo_.push_back(Eigen::Index(lo));
            interpHi_.push_back(Eigen::Index(hi));
            interpT_.push_back(lo == hi ? 0.f : float(kk - k[lo]) / float(k[hi] - k[lo]));
        }
        Ls_ = std::min<unsigned>(opts_.smoothingLength, unsigned(gridK_.size()) / 2);
        const Eigen::Index nRx = f.nRx, Ls = Ls_, shifts = Eigen::Index(gridK_.size()) - Ls + 1;
        U_.resize(nRx, Eigen::Index(gridK_.size()));
        Xs_.resize(nRx * Ls, shifts);
        Ej_.resize(nRx, Ls);
        DmConj_.resize(Ls, Eigen::Index(delays_.size()));
        for (Eigen::Index l = 0; l < Ls; ++l)
            for (size_t d = 0; d < delays_.size(); ++d)
                DmConj_(l, Eigen::Index(d)) = std::conj(std::complex<float>(std::polar(
                    1.0, -2 * M_PI * double(l) * step_ * kSubcarrierSpacingHz * delays_[d])));
        Bq_ = quadraticFormBasis(rx_, size_t(nRx), grid_, f.layout->centerFrequency_Hz);
    }

public:
    struct Candidate
    {
        double theta, delay, power;
    };
    /** The 2-D MUSIC peaks of the last estimate (bearing, delay, Bartlett power). */
    const std::vector<Candidate>& candidates() const { return cands_; }

protected:
    std::vector<Candidate> cands_;
    uint64_t cacheOwner_ = 0;  //!< CleanCsi::derived() key of the smoothed covariances
    double step_ = 4;
    unsigned Ls_ = 16;
    std::vector<int> gridK_;
    std::vector<Eigen::Index> interpLo_, interpHi_;
    std::vector<float> interpT_;
    Eigen::MatrixXcf U_, Xs_, Rs_, Ej_, DmConj_, V_;
    Eigen::MatrixXf Bq_, coeffs_, proj_, pseudo_;
    Eigen::MatrixXcd RsD_;
    TopEigenvectors eig_;
};

// =============================================================================================
/** (0) The recommended default: the 2-D bearing × delay profile of an 8-frame window (frames
 *  combined while the robot moves decorrelate the reflections), SpotFi's delay rule done on the
 *  robust matched-filter profile (among the peaks with at least `direct_path_power_ratio` of the
 *  strongest one's power, the earliest delay is the direct path; peaks within 5 ns of it, which
 *  the band can't separate, go to the strongest), the bearing polished with per-sub-band
 *  wavelengths on the CSI matched to that delay, and a σ that includes what the same delay
 *  also supports (the other endfire, a path the band can't separate). AoD as the aod
 *  estimator's, when the transmitter sends several streams and its array is known. */
class DefaultEstimator : public ProfileEstimator
{
public:
    DefaultEstimator()
    {
        opts_.window = 8;
        opts_.directPathPowerRatio = 0.5;
    }
    std::string name() const override { return "default"; }
    std::string description() const override
    {
        return "recommended: 8-frame angle x delay profile, earliest strong path, honest sigma "
               "(+ AoD of a multi-stream transmitter with a known array)";
    }
    std::vector<std::string> parameterKeys() const override
    {
        return plus(plus(kCommon1D, kProfileKeys), {"direct_path_power_ratio", "aod_method"});
    }

    bool estimate(
        const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx,
        BearingResult& r) override
    {
        r = BearingResult();
        if (!prepare(frames, ctx)) return false;
        profile2d_.reset();
        double energy = 0;
        for (const auto* f : frames)
        {
            profile2d_.accumulate(*f);
            energy += f->H.squaredNorm();
        }
        const Eigen::MatrixXf& P = profile2d_.power();
        const auto peaks = findPeaks2D(P, grid_.circular, 4);
        if (peaks.empty()) return false;
        struct Candidate
        {
            double theta, delay, power;
            bool competes;  //!< may be taken for the direct path
        };
        std::vector<Candidate> cands;
        double maxPower = 0;
        for (const auto& p0 : peaks)
        {
            const Peak2D p = refinePeak2D(P, p0.i, p0.j, grid_.circular);
            // A weaker peak on a linear array's last row (an endfire) is no earlier path: the
            // array cannot place a direction there (its bearing error grows without bound),
            // and on real RT-AC86U captures at 20 MHz the inter-chain delays a calibration
            // leaves put peaks on both endfires at earlier delays than the path's (issue 54:
            // muTrack D1, -90 deg in every window of a device 5 deg off broadside).
            const bool endfireRow = !grid_.circular && (p0.i == 0 || p0.i + 1 == size_t(P.rows()));
            cands.push_back(
                {grid_.at(p.fi), delayAt(delays_, p.fj), p.value, cands.empty() || !endfireRow});
            maxPower = std::max(maxPower, double(p.value));
        }
        constexpr double kSameDelay_s = 5e-9, kCleanPath = 0.97;
        constexpr double kReferenceBand_Hz = 244 * kSubcarrierSpacingHz;  // 80 MHz: k = ±122
        double earliest = INFINITY;
        for (const auto& c : cands)
            if (c.competes && c.power >= opts_.directPathPowerRatio * maxPower)
                earliest = std::min(earliest, c.delay);
        Candidate chosen{0, 0, -1, true};
        for (const auto& c : cands)
            if (c.competes && c.power >= opts_.directPathPowerRatio * maxPower &&
                c.delay <= earliest + kSameDelay_s && c.power > chosen.power)
                chosen = c;
        double theta = chosen.theta;
        delayFilteredCovariances(frames, chosen.delay, opts_.frequencyGroups, Rd_);
        if (opts_.refine) theta = polishBartlett(theta, Rd_);
        // Super-resolution: the 2-D MUSIC peak of the same path, when there is one, separates
        // it from the paths the matched filter blurs into it (only where a plane wave leaves
        // power unexplained at that delay: a clean path needs none).
        const double cleanness = bartlettQuality(fastGroupedForm(theta, Rd_), Rd_, rx_.size());
        // Its delay agrees with the profile's to within a share of the band's delay resolution
        // (10 ns at 80 MHz; 4.4× that at 20 MHz, where the two delays of the same path differ
        // by tens of ns and the refinement never applied: issue 54, muTrack D1).
        const double band_Hz = layout_->frequencies_Hz.back() - layout_->frequencies_Hz.front();
        const double samePathDelay_s =
            2 * kSameDelay_s * std::max(1.0, kReferenceBand_Hz / std::max(band_Hz, 1.0));
        if (cleanness < kCleanPath && spotfi_.estimate(frames, ctx, spotfiResult_))
        {
            double bestD = 0.2 * beamwidth();
            for (const auto& c : spotfi_.candidates())
            {
                const double d = foldedDistance(theta, c.theta);
                if (d < bestD && std::abs(c.delay - chosen.delay) < samePathDelay_s)
                {
                    bestD = d;
                    theta =
                        angleDistance(theta, c.theta) <= d + 1e-9 ? c.theta : rx_.mirrorOf(c.theta);
                }
            }
        }
        const double drift = followWindowDrift(frames, chosen.delay, theta);
        sumCovariances(frames, opts_.frequencyGroups, false, R_);
        const auto paths = otherPaths(cands, chosen);
        finish(r, theta, R_, frames, &Rd_, &paths);
        widenByDrift(r, drift);
        const double nSub = double(layout_->size());
        r.quality = std::clamp(chosen.power / (double(rx_.size()) * nSub * energy), 0.0, 1.0);
        r.hasDelay = true;
        r.delay_s = chosen.delay;
        r.pathsDetected = unsigned(cands.size());
        keep2D(P, "Bartlett power", r.aoa_rad, chosen.delay);
        if (hasProfile_) profile_.peakAngle_rad = theta;
        estimateAod(frames, ctx, r);
        return true;
    }

private:
    SpotFiEstimator spotfi_;
    BearingResult spotfiResult_;
};

// =============================================================================================
/** (6) AoD (EstimatorBase::estimateAod) with the fast AoA of aoa_only. */
class AodEstimator : public EstimatorBase
{
public:
    std::string name() const override { return "aod"; }
    std::string description() const override
    {
        return "AoD from the transmitter's streams with its array geometry (+ fast AoA)";
    }
    std::vector<std::string> parameterKeys() const override
    {
        return plus(plus(kCommon1D, kSubspaceKeys), {"aod_method"});
    }

    bool estimate(
        const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx,
        BearingResult& r) override
    {
        r = BearingResult();
        if (!prepare(frames, ctx)) return false;
        // Receive side: as aoa_only.
        sumCovariances(frames, opts_.frequencyGroups, false, R_);
        qf_.evaluate(R_, spec_);
        Eigen::Index best;
        spec_.maxCoeff(&best);
        double theta = grid_.at(refinePeak1D(spec_, size_t(best), grid_.circular));
        if (opts_.refine) theta = polishBartlett(theta, R_);
        finish(r, theta, R_, frames);
        r.pathsDetected = 1;
        keep1D(spec_, "Bartlett power (AoA)", theta);

        estimateAod(frames, ctx, r);
        return true;
    }
};

// =============================================================================================
/** (7) ESPRIT (not in WiROS): grid-free, from the rotational invariance between two copies of
 *  the array displaced by d (found in the geometry: the rt-ac86u line has three pairs 26 mm
 *  apart). The signal subspace of the frequency-smoothed covariance gives e^{j2π f/c d·u} per
 *  path by least squares; a 2-D array with two independent displacements gives both components
 *  of u (paired through the eigenvectors of the first). The strongest path (Bartlett power) is
 *  reported. */
class EspritEstimator : public EstimatorBase
{
public:
    std::string name() const override { return "esprit"; }
    std::string description() const override
    {
        return "ESPRIT: grid-free super-resolution from the array's shift invariance";
    }
    std::vector<std::string> parameterKeys() const override
    {
        return plus({"window", "frequency_groups", "std_floor_deg", "angle_bins"}, kSubspaceKeys);
    }

    bool estimate(
        const std::vector<const CleanCsi*>& frames, const EstimatorContext& ctx,
        BearingResult& r) override
    {
        r = BearingResult();
        if (!prepare(frames, ctx)) return false;
        if (shifts_.empty())
            throw std::invalid_argument(
                "esprit: array '" + rx_.name +
                "' has no two elements a common displacement "
                "apart; use music or aoa_only");
        sumCovariances(frames, opts_.frequencyGroups, false, R_);
        Eigen::MatrixXcd total = R_[0];
        for (size_t g = 1; g < R_.size(); ++g) total += R_[g];
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> es(total);
        unsigned K = signalDimension(es.eigenvalues(), opts_.subspaceThreshold, opts_.maxPaths);
        K = std::min<unsigned>(K, unsigned(shifts_[0].from.size()));
        if (shifts_.size() > 1) K = std::min<unsigned>(K, unsigned(shifts_[1].from.size()));
        const Eigen::MatrixXcd Es = es.eigenvectors().rightCols(K);

        const auto rotation = [&](const Shift& s)
        {
            Eigen::MatrixXcd E1(s.from.size(), K), E2(s.from.size(), K);
            for (size_t p = 0; p < s.from.size(); ++p)
            {
                E1.row(Eigen::Index(p)) = Es.row(Eigen::Index(s.from[p]));
                E2.row(Eigen::Index(p)) = Es.row(Eigen::Index(s.to[p]));
            }
            return Eigen::MatrixXcd(E1.completeOrthogonalDecomposition().solve(E2));
        };
        const double k0 = 2 * M_PI * fc_ / kSpeedOfLightMps;
        const Eigen::MatrixXcd Psi1 = rotation(shifts_[0]);
        Eigen::ComplexEigenSolver<Eigen::MatrixXcd> ces(Psi1);
        // The rt-ac86u's 26 mm is just over λ/2 at 5.8 GHz: a rotation phase near ±π may have
        // wrapped. Both unwrappings are candidates; the wideband Bartlett power decides.
        const auto unwrappings = [](double psi) {
            return std::array<double, 2>{psi, psi - 2 * M_PI * (psi > 0 ? 1 : -1)};
        };
        std::vector<double> thetas;
        if (shifts_.size() == 1)
        {
            const Shift& s = shifts_[0];
            for (Eigen::Index q = 0; q < Eigen::Index(K); ++q)
            {
                double bestT = 0, bestP = -1;
                for (double psi : unwrappings(std::arg(ces.eigenvalues()[q])))
                {
                    const double c = psi / k0 / s.length;  // cos of the angle to d
                    if (std::abs(c) > 1.1) continue;
                    const double t = s.direction + std::acos(std::clamp(c, -1.0, 1.0));
                    const double pw = fastGroupedForm(t, R_);
                    if (pw > bestP) bestP = pw, bestT = t;
                }
                thetas.push_back(bestT);  // setAoa folds it to the front half-plane
            }
        }
        else
        {
            const Eigen::MatrixXcd T = ces.eigenvectors();
            const Eigen::MatrixXcd Psi2 = rotation(shifts_[1]);
            const Eigen::MatrixXcd L2 = T.inverse() * Psi2 * T;
            Eigen::Matrix2d Dm;
            Dm << shifts_[0].d.x, shifts_[0].d.y, shifts_[1].d.x, shifts_[1].d.y;
            const auto qr = Dm.colPivHouseholderQr();
            for (Eigen::Index q = 0; q < Eigen::Index(K); ++q)
            {
                double bestT = 0, bestP = -1;
                for (double p1 : unwrappings(std::arg(ces.eigenvalues()[q])))
                    for (double p2 : unwrappings(std::arg(L2(q, q))))
                    {
                        const Eigen::Vector2d u = qr.solve(Eigen::Vector2d(p1 / k0, p2 / k0));
                        if (u.norm() < 0.5 || u.norm() > 1.5) continue;  // not a plane wave
                        const double t = std::atan2(u.y(), u.x());
                        const double pw = fastGroupedForm(t, R_);
                        if (pw > bestP) bestP = pw, bestT = t;
                    }
                thetas.push_back(bestT);
            }
        }
        double best = 0, bestPower = -1;
        for (double t : thetas)
        {
            const double power = fastGroupedForm(t, R_);
            if (power > bestPower)
            {
                bestPower = power;
                best = t;
            }
        }
        finish(r, best, R_, frames);
        r.pathsDetected = K;
        hasProfile_ = false;
        return true;
    }

private:
    struct Shift
    {
        mrpt::math::TPoint2D d;
        double length = 0, direction = 0;
        std::vector<size_t> from, to;
    };

    void onPrepare(const CleanCsi& f) override
    {
        fc_ = f.layout->centerFrequency_Hz;
        // Displacements between element pairs, with all pairs sharing each one.
        std::vector<Shift> all;
        const auto& e = rx_.elements;
        for (size_t i = 0; i < e.size(); ++i)
            for (size_t j = 0; j < e.size(); ++j)
            {
                if (i == j) continue;
                const auto d = e[j] - e[i];
                // One of ±d: the one pointing into [0, π).
                const double dir = std::atan2(d.y, d.x);
                if (!(dir >= -1e-9 && dir < M_PI - 1e-9)) continue;
                auto it = std::find_if(
                    all.begin(), all.end(),
                    [&](const Shift& s) { return (s.d - d).norm() < 1e-4; });
                if (it == all.end())
                {
                    all.push_back(Shift{d, d.norm(), dir, {}, {}});
                    it = all.end() - 1;
                }
                it->from.push_back(i);
                it->to.push_back(j);
            }
        // Most pairs first; among equals the shortest (least aliasing).
        std::sort(
            all.begin(), all.end(),
            [](const Shift& a, const Shift& b) {
                return a.from.size() != b.from.size() ? a.from.size() > b.from.size()
                                                      : a.length < b.length;
            });
        shifts_.clear();
        if (!all.empty()) shifts_.push_back(all[0]);
        const bool linear = rx_.isLinear();
        if (!linear)
            for (size_t s = 1; s < all.size(); ++s)
            {
                const auto& a = all[0].d;
                const auto& b = all[s].d;
                if (std::abs(a.x * b.y - a.y * b.x) > 1e-6 * a.norm() * b.norm())
                {
                    shifts_.push_back(all[s]);
                    break;
                }
            }
    }

    double fc_ = 0;
    std::vector<Shift> shifts_;
};

}  // namespace

std::vector<std::string> arrayEstimatorNames()
{
    return {"default", "aoa_only", "fft", "svd", "music", "spotfi", "aod", "esprit"};
}

std::vector<std::string> estimatorNames()
{
    auto names = arrayEstimatorNames();
    names.push_back("sar");
    return names;
}

std::unique_ptr<BearingEstimator> createEstimator(
    const std::string& name, const mrpt::containers::yaml& params)
{
    std::unique_ptr<BearingEstimator> e;
    if (name == "default")
        e = std::make_unique<DefaultEstimator>();
    else if (name == "aoa_only")
        e = std::make_unique<AoaOnlyEstimator>();
    else if (name == "fft")
        e = std::make_unique<ProfileEstimator>();
    else if (name == "svd")
        e = std::make_unique<SvdEstimator>();
    else if (name == "music")
        e = std::make_unique<MusicEstimator>();
    else if (name == "spotfi")
        e = std::make_unique<SpotFiEstimator>();
    else if (name == "aod")
        e = std::make_unique<AodEstimator>();
    else if (name == "esprit")
        e = std::make_unique<EspritEstimator>();
    else if (name == "sar")
        e = std::make_unique<sar::SyntheticApertureEstimator>();
    else
    {
        std::string list;
        for (const auto& n : estimatorNames()) list += (list.empty() ? "" : ", ") + n;
        throw std::invalid_argument(
            "unknown bearing algorithm '" + name + "' (known: " + list + ")");
    }
    e->configure(params);
    return e;
}

}  // namespace mrpt_wifi::bearing
