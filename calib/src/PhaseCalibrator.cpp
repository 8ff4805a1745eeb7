/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <ceres/ceres.h>
#include <mrpt_wifi/calib/CalibrationCheck.h>
#include <mrpt_wifi/calib/PhaseCalibrator.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <set>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::calib
{
using cd = std::complex<double>;

PreprocessOptions calibrationPreprocessOptions()
{
    PreprocessOptions o;
    o.correctSubbandSign80 = true;
    o.excludeFirmwareOverwritten = true;
    o.removeSamplingTimeOffset = true;  // common to antennas: harmless, and keeps pools tidy
    o.normalizePower = true;            // every frame weighs the same in the covariances
    o.requireCalibration = false;
    o.trackChainStates = true;  // frames are grouped by the receive chains' jump states
    // A state found late leaves its first frames in another state, whose offsets they pull
    // (6.6° RMS instead of 1.5° on CalibSim.PerStateOffsetsWithTheCalibratorsOwnStates): the
    // calibration finds states on 16 of 24 far frames instead of 20. Live tracking keeps 20,
    // which finds fewer spurious states in multipath; a spurious state in a drive gets too few
    // frames to be calibrated (minStateFrames).
    o.chainStates.discoveryVotes = 16;
    return o;
}

// ---------------------------------------------------------------------------------------------
namespace
{
PreprocessOptions withoutStateTracking(PreprocessOptions o)
{
    o.trackChainStates = false;
    return o;
}
}  // namespace

FramePreparer::FramePreparer(AntennaArray array, PreprocessOptions opts)
    : pre_(withoutStateTracking(opts), std::move(array), CalibrationStore()),
      trackStates_(opts.trackChainStates),
      stateOptions_(opts.chainStates)
{
}

std::vector<const ChainStateTracker*> FramePreparer::chainStateTrackers() const
{
    std::vector<const ChainStateTracker*> out;
    for (const auto& [key, t] : trackers_) out.push_back(&t);
    return out;
}

RejectReason FramePreparer::common(const CObservationWiFiCSI& obs, CalibrationFrame& out)
{
    const RejectReason r = pre_.process(obs, clean_);
    if (r != RejectReason::Accepted) return r;
    out.time_s = mrpt::Clock::toDouble(obs.timestamp);
    out.transmitter = obs.transmitter;
    out.chanspec = obs.chanspec;
    out.rssi_dBm = obs.rssi_dBm;
    out.nRx = clean_.nRx;
    out.nTx = clean_.nTx;
    out.layout = clean_.layout;
    out.H = clean_.H;
    out.hasGeometry = false;
    out.chainDelay_s.clear();
    out.chainState.clear();
    if (trackStates_ && clean_.nRx >= 2)
    {
        const Chanspec& cs = clean_.layout->chanspec;
        const auto key = std::make_pair(
            (uint32_t(cs.centerChannel) << 16) | cs.bandwidthMHz, unsigned(clean_.nRx));
        auto it = trackers_.find(key);
        if (it == trackers_.end())
            it =
                trackers_
                    .emplace(
                        key, ChainStateTracker(clean_.nRx, nullptr, stateOptions_, cs.bandwidthMHz))
                    .first;
        measureChainDelays(
            clean_.H, clean_.nRx, clean_.layout->subcarriers, out.chainDelay_s, coherence_);
        it->second.classify(out.chainDelay_s, coherence_, out.chainState);
    }
    return r;
}

bool removeChainStates(const PhaseCalibration& c, CalibrationFrame& f)
{
    if (c.chainStates.empty()) return true;
    if (f.chainDelay_s.size() < f.nRx || !f.layout) return false;
    bool all = true;
    for (unsigned i = 1; i < f.nRx; ++i)
    {
        const ChainStateCalibration* st = c.matchChainState(i, f.chainDelay_s[i]);
        if (!st)
        {
            all = false;
            continue;
        }
        const double w = 2 * M_PI * kSubcarrierSpacingHz * st->deltaDelay_s;
        for (unsigned m = 0; m < f.nTx; ++m)
            for (size_t j = 0; j < f.layout->size(); ++j)
                f.H(Eigen::Index(m * f.nRx + i), Eigen::Index(j)) *= std::complex<float>(
                    std::polar(1.0, w * f.layout->subcarriers[j] - st->deltaPhase_rad));
    }
    return all;
}

ChainStatePolicy chainStatePolicyFromString(const std::string& s, const std::string& what)
{
    if (s == "auto") return ChainStatePolicy::Auto;
    if (s == "on") return ChainStatePolicy::Always;
    if (s == "off") return ChainStatePolicy::Never;
    throw std::invalid_argument(what + ": expected auto, on or off, got '" + s + "'");
}

std::string applyChainStatePolicy(PhaseCalibration& c, ChainStatePolicy policy, double maxPhase_rad)
{
    if (c.chainStates.empty() || policy == ChainStatePolicy::Always) return {};
    const bool onlyReferences = std::all_of(
        c.chainStates.begin(), c.chainStates.end(),
        [](const ChainStateCalibration& st)
        { return st.deltaDelay_s == 0 && st.deltaPhase_rad == 0; });
    if (policy == ChainStatePolicy::Auto && onlyReferences)
    {
        // No chain jumped during the drive: the file is one without states, each chain's delay
        // kept in its phases (a table of reference states would only make the bearing chain
        // match over-the-air delays, biased by multipath, to the drive's).
        c.chainStates.clear();
        return "no chain changed state during the drive: no state table written";
    }
    double largest = 0;
    for (const auto& st : c.chainStates) largest = std::max(largest, std::abs(st.deltaPhase_rad));
    std::ostringstream o;
    o.precision(1);
    o << std::fixed;
    if (policy == ChainStatePolicy::Never)
        o << c.chainStates.size() << " jump states not written (--chain-states off)";
    else if (largest <= maxPhase_rad)
        o << "the " << c.chainStates.size()
          << " jump states differ by a delay alone (phase at the centre within "
          << largest * 180 / M_PI << " deg): not written, the offsets hold in every state "
          << "(--chain-states on writes them)";
    else
        return {};
    // Said in the file, so the bearing chain knows the states were seen and need nothing. What
    // holds in every state is each chain's phase at the centre frequency and its ripple: the
    // reference state's delay (a slope across subcarriers) is taken out of the phases, as a
    // frame over the air sits in any state (and its multipath shifts the delay further).
    c.chainStatesDelayOnly = policy == ChainStatePolicy::Auto;
    if (c.chainStatesDelayOnly)
        for (const auto& st : c.chainStates)
        {
            if (st.deltaDelay_s != 0 || st.antenna >= c.phases_rad.size()) continue;  // reference
            auto& row = c.phases_rad[st.antenna];
            for (size_t j = 0; j < row.size() && j < c.subcarriers.size(); ++j)
                row[j] += 2 * M_PI * kSubcarrierSpacingHz * c.subcarriers[j] * st.delay_s;
        }
    c.chainStates.clear();
    return o.str();
}

RejectReason FramePreparer::prepare(
    const CObservationWiFiCSI& obs, const mrpt::math::TPose2D& robotPose,
    const mrpt::math::TPoint2D& transmitter, CalibrationFrame& out)
{
    const RejectReason r = common(obs, out);
    if (r != RejectReason::Accepted) return r;
    // Receive array in the world: robot ⊕ mounting (planar part).
    const double c = std::cos(robotPose.phi), s = std::sin(robotPose.phi);
    const auto& sp = obs.sensorPose;
    out.sensorPose.x = robotPose.x + c * sp.x() - s * sp.y();
    out.sensorPose.y = robotPose.y + s * sp.x() + c * sp.y();
    out.sensorPose.phi = wrapAngle(robotPose.phi + sp.yaw());
    const double dx = transmitter.x - out.sensorPose.x, dy = transmitter.y - out.sensorPose.y;
    out.distance_m = std::hypot(dx, dy);
    out.expectedAoa_rad = wrapAngle(std::atan2(dy, dx) - out.sensorPose.phi);
    out.hasGeometry = true;
    return r;
}

RejectReason FramePreparer::prepareStatic(const CObservationWiFiCSI& obs, CalibrationFrame& out)
{
    return common(obs, out);
}

// ---------------------------------------------------------------------------------------------
bool TransmitChainFramer::make(
    const CalibrationFrame& f, const mrpt::math::TPose2D& ap, unsigned chains,
    CalibrationFrame& out)
{
    if (!f.hasGeometry || !f.layout || f.nTx != chains || chains < 2) return false;
    auto& nb = narrowband_[f.layout.get()];
    if (!nb)
    {
        auto l = std::make_shared<SubcarrierLayout>(*f.layout);
        std::fill(l->frequencies_Hz.begin(), l->frequencies_Hz.end(), l->centerFrequency_Hz);
        nb = l;
    }
    out.time_s = f.time_s;
    out.transmitter = f.transmitter;
    out.chanspec = f.chanspec;
    out.rssi_dBm = f.rssi_dBm;
    out.nRx = f.nTx;
    out.nTx = f.nRx;
    out.layout = nb;
    out.H.resize(f.H.rows(), f.H.cols());
    for (unsigned i = 0; i < f.nRx; ++i)
        for (unsigned m = 0; m < f.nTx; ++m)
            out.H.row(Eigen::Index(i * f.nTx + m)) = f.H.row(Eigen::Index(m * f.nRx + i));
    const double dx = f.sensorPose.x - ap.x, dy = f.sensorPose.y - ap.y;
    out.distance_m = std::hypot(dx, dy);
    out.expectedAoa_rad = wrapAngle(std::atan2(dy, dx) - ap.phi);
    out.sensorPose = f.sensorPose;
    out.hasGeometry = true;
    return true;
}

// ---------------------------------------------------------------------------------------------
Eigen::MatrixXcf calibrationFactors(
    const PhaseCalibration& c, const SubcarrierLayout& layout, unsigned nRx)
{
    if (c.antennas() < nRx)
        throw CalibrationError(
            "the calibration '" + c.sourcePath + "' has " + std::to_string(c.antennas()) +
            " antennas, the CSI " + std::to_string(nRx));
    Eigen::MatrixXcf f(nRx, Eigen::Index(layout.size()));
    for (unsigned i = 0; i < nRx; ++i)
    {
        const double g = std::pow(10.0, -c.gainAt(i) / 20.0);
        for (size_t j = 0; j < layout.size(); ++j)
            f(i, Eigen::Index(j)) =
                std::complex<float>(std::polar(g, -c.phaseAt(i, layout.subcarriers[j])));
    }
    return f;
}

// ---------------------------------------------------------------------------------------------
PhaseCalibrator::PhaseCalibrator(AntennaArray array, CalibratorOptions opts)
    : array_(std::move(array)), opts_(opts)
{
}

namespace
{
/** Expected bearing as a linear array can see it (mirror folded into its half-plane). */
double foldBearing(const AntennaArray& a, double theta)
{
    if (!a.isLinear() || a.size() < 2) return wrapAngle(theta);
    const auto [lo, hi] = a.searchInterval();
    const double centre = 0.5 * (lo + hi);
    const double rel = wrapAngle(theta - centre);
    if (rel >= -0.5 * (hi - lo) && rel < 0.5 * (hi - lo)) return wrapAngle(theta);
    return a.mirrorOf(theta);
}
}  // namespace

void PhaseCalibrator::add(const CalibrationFrame& f)
{
    if (opts_.mode == CalibrationMode::Drive && !f.hasGeometry)
        throw std::invalid_argument("drive calibration needs frames with an expected bearing");
    if (f.nRx > array_.size())
        throw std::invalid_argument(
            "the CSI has " + std::to_string(f.nRx) + " receive chains, the array '" + array_.name +
            "' only " + std::to_string(array_.size()) + " elements");
    if (!f.layout || f.H.rows() != Eigen::Index(f.nRx * f.nTx) ||
        f.H.cols() != Eigen::Index(f.layout->size()))
        throw std::invalid_argument("malformed calibration frame");

    Channel& ch = channels_[key(f.chanspec)];
    const unsigned n = f.nRx;
    const size_t nSub = f.layout->size();
    // A chain whose state this frame could not tell stays in its last known state (the states
    // last seconds); before any is known the frame can't be grouped and is left out. So is a
    // frame whose delay lies far from that state's: it is in another state the classifier has
    // not caught up with yet (it lags a switch by a few frames), and would pull the old
    // state's offsets (by 1–2 ns on the muTrack captures' 12.5 ns states).
    const double tolerance_s =
        ChainStateOptions().tolerance_s * chainStateDelayScale(f.chanspec.bandwidthMHz);
    std::vector<uint8_t> chainState = f.chainState;
    for (size_t i = 0; i < chainState.size(); ++i)
        if (chainState[i] == kUnknownChainState)
        {
            if (i >= ch.lastStates.size() || ch.lastStates[i] == kUnknownChainState)
            {
                ++ch.unknownStateFrames;
                return;
            }
            const auto last = ch.states.find({unsigned(i), ch.lastStates[i]});
            if (last != ch.states.end() && last->second.frames > 0 && i < f.chainDelay_s.size() &&
                std::isfinite(f.chainDelay_s[i]) &&
                std::abs(
                    f.chainDelay_s[i] - last->second.delaySum_s / double(last->second.frames)) >
                    tolerance_s)
            {
                ++ch.unknownStateFrames;
                return;
            }
            chainState[i] = ch.lastStates[i];
        }
    if (!ch.layout)
    {
        ch.layout = f.layout;
        ch.nRx = n;
        ch.antennaPower = Eigen::VectorXd::Zero(n);
        ch.tFirst = f.time_s;
    }
    else if (ch.nRx != n || ch.layout->size() != nSub)
        throw std::invalid_argument(
            "frames on " + f.chanspec.asString() + " change shape (" + std::to_string(ch.nRx) +
            " → " + std::to_string(n) + " antennas)");

    // One open segment per transmitter: a pose error shifts each transmitter's bearings its own
    // way, and two transmitters pooled in one covariance would make it rank two.
    // One jump state per chain per segment, so each state's correction applies to whole
    // segments.
    const auto open = ch.openSegment.find(f.transmitter);
    if (open == ch.openSegment.end() || f.time_s - ch.segments[open->second].t0 > opts_.segment_s ||
        f.time_s < ch.segments[open->second].t0 ||
        ch.segments[open->second].chainState != chainState)
    {
        Segment s;
        s.t0 = f.time_s;
        s.transmitter = f.transmitter;
        s.chainState = chainState;
        s.R.assign(nSub, Eigen::MatrixXcd::Zero(n, n));
        ch.segments.push_back(std::move(s));
        ch.openSegment[f.transmitter] = ch.segments.size() - 1;
    }
    Segment& seg = ch.segments[ch.openSegment[f.transmitter]];

    // Suppression by the expected steering (drive mode): conj(a_i(θ, f_k)).
    Eigen::MatrixXcf conjSteer;
    if (f.hasGeometry && opts_.mode == CalibrationMode::Drive)
    {
        conjSteer.resize(n, Eigen::Index(nSub));
        for (unsigned i = 0; i < n; ++i)
        {
            const double p = 2 * M_PI * array_.projection(i, f.expectedAoa_rad) / kSpeedOfLightMps;
            for (size_t j = 0; j < nSub; ++j)
                conjSteer(i, Eigen::Index(j)) =
                    std::complex<float>(std::polar(1.0, -p * f.layout->frequencies_Hz[j]));
        }
    }

    std::vector<cd> x(n);
    for (unsigned m = 0; m < f.nTx; ++m)
    {
        for (size_t j = 0; j < nSub; ++j)
        {
            for (unsigned i = 0; i < n; ++i)
            {
                std::complex<float> h = f.H(Eigen::Index(m * n + i), Eigen::Index(j));
                ch.antennaPower[i] += std::norm(h);
                if (conjSteer.size()) h *= conjSteer(i, Eigen::Index(j));
                x[i] = cd(h);
            }
            auto& R = seg.R[j];
            for (unsigned a = 0; a < n; ++a)
                for (unsigned b = a; b < n; ++b) R(a, b) += x[a] * std::conj(x[b]);
        }
        ++ch.snapshots;
    }
    ++seg.frames;
    ++ch.frames;
    ch.tLast = f.time_s;
    for (unsigned i = 1; i < chainState.size() && i < f.chainDelay_s.size(); ++i)
    {
        auto& st = ch.states[{i, chainState[i]}];
        ++st.frames;
        st.delaySum_s += f.chainDelay_s[i];
    }
    if (!ch.lastStates.empty() && ch.lastStates != chainState) ++ch.stateChanges;
    ch.lastStates = chainState;
    if (f.hasGeometry)
    {
        ch.foldedAoa.push_back(float(foldBearing(array_, f.expectedAoa_rad)));
        ch.distance.push_back(float(f.distance_m));
    }

    // Keep an evenly spread subset for the before/after bearing errors.
    if (opts_.checkFrames > 0 && (ch.seen++ % ch.keepStride) == 0)
    {
        ch.kept.push_back(f);
        if (ch.kept.size() >= 2 * opts_.checkFrames)
        {
            std::vector<CalibrationFrame> half;
            half.reserve(opts_.checkFrames);
            for (size_t i = 0; i < ch.kept.size(); i += 2) half.push_back(std::move(ch.kept[i]));
            ch.kept = std::move(half);
            ch.keepStride *= 2;
        }
    }
}

std::vector<Chanspec> PhaseCalibrator::channels() const
{
    std::vector<Chanspec> r;
    for (const auto& [k, ch] : channels_) r.push_back(ch.layout->chanspec);
    return r;
}

size_t PhaseCalibrator::frames(const Chanspec& cs) const
{
    const auto it = channels_.find(key(cs));
    return it == channels_.end() ? 0 : it->second.frames;
}

namespace
{
/** Misfit of unit-modulus weights v = (1, e^{jφ_1}, ..., e^{jφ_{n−1}}) against one pooled
 *  covariance: r = L·v with L^H L = (λ0·I − R)/(n·N). |r|² is the power the calibrated line of
 *  sight leaves unexplained beyond what no v can explain, per snapshot; 0 at the best v. */
class OrthogonalSubspaceCost final : public ceres::CostFunction
{
public:
    explicit OrthogonalSubspaceCost(Eigen::MatrixXcd L) : L_(std::move(L))
    {
        set_num_residuals(int(2 * L_.rows()));
        mutable_parameter_block_sizes()->push_back(int(L_.cols() - 1));
    }

    bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override
    {
        const Eigen::Index n = L_.cols(), m = L_.rows();
        Eigen::VectorXcd v(n);
        v[0] = 1.0;
        for (Eigen::Index i = 1; i < n; ++i) v[i] = std::polar(1.0, params[0][i - 1]);
        const Eigen::VectorXcd r = L_ * v;
        for (Eigen::Index q = 0; q < m; ++q)
        {
            residuals[q] = r[q].real();
            residuals[m + q] = r[q].imag();
        }
        if (jacobians && jacobians[0])
        {
            // ∂r/∂φ_i = L(:, i) · j·v_i ; row-major (2m) × (n−1).
            double* J = jacobians[0];
            for (Eigen::Index i = 1; i < n; ++i)
            {
                const cd jv = cd(0, 1) * v[i];
                for (Eigen::Index q = 0; q < m; ++q)
                {
                    const cd d = L_(q, i) * jv;
                    J[q * (n - 1) + (i - 1)] = d.real();
                    J[(m + q) * (n - 1) + (i - 1)] = d.imag();
                }
            }
        }
        return true;
    }

private:
    Eigen::MatrixXcd L_;
};

Eigen::MatrixXcd hermitian(const Eigen::MatrixXcd& upper)
{
    Eigen::MatrixXcd R = upper;
    for (Eigen::Index a = 0; a < R.rows(); ++a)
    {
        R(a, a) = R(a, a).real();
        for (Eigen::Index b = 0; b < a; ++b) R(a, b) = std::conj(R(b, a));
    }
    return R;
}

Eigen::VectorXcd unitWeights(const std::vector<double>& phi, size_t j, size_t nSub, unsigned n)
{
    Eigen::VectorXcd v(n);
    v[0] = 1.0;
    for (unsigned i = 1; i < n; ++i) v[i] = std::polar(1.0, phi[(i - 1) * nSub + j]);
    return v;
}

std::string isoNow()
{
    const std::time_t t = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&t, &tm);
    char buf[32];
    std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

std::string fmt(double v, int prec = 1)
{
    std::ostringstream o;
    o.setf(std::ios::fixed);
    o.precision(prec);
    o << v;
    return o.str();
}
}  // namespace

size_t PhaseCalibrator::minStateFrames(size_t frames) const
{
    return std::max<size_t>(opts_.minStateFrames, size_t(opts_.minStateShare * double(frames)));
}

ChannelCalibration PhaseCalibrator::solve(const Chanspec& cs) const
{
    const auto it = channels_.find(key(cs));
    if (it == channels_.end() || it->second.frames == 0)
        throw std::runtime_error("no calibration frames on " + cs.asString());
    const Channel& ch = it->second;
    const unsigned n = ch.nRx;
    const size_t nSub = ch.layout->size();
    if (n < 2)
        throw std::runtime_error("one receive antenna: there is no relative phase to calibrate");
    const bool drive = opts_.mode == CalibrationMode::Drive;
    const auto t0 = std::chrono::steady_clock::now();

    ChannelCalibration out;
    auto& d = out.diag;

    // Jump states: each chain's most visited state is its reference; every other state is
    // measured against it from the pooled, bearing-suppressed cross products with antenna 0
    // (the drive is the same, only the grouping changes), then each segment's covariances are
    // turned into the reference states so one fit uses every frame.
    std::map<std::pair<unsigned, uint8_t>, ChainStateDiagnostics> states;
    std::vector<uint8_t> referenceState(n, 0);
    for (unsigned i = 1; i < n; ++i)
    {
        size_t most = 0;
        for (const auto& [key, st] : ch.states)
            if (key.first == i && st.frames > most)
                most = st.frames, referenceState[i] = key.second;
    }
    const auto crossProducts = [&](unsigned i, uint8_t state)
    {
        Eigen::MatrixXcf c = Eigen::MatrixXcf::Zero(1, Eigen::Index(nSub));
        for (const auto& s : ch.segments)
            if (s.chainState.size() > i && s.chainState[i] == state)
                for (size_t j = 0; j < nSub; ++j)
                    c(0, Eigen::Index(j)) += std::complex<float>(std::conj(s.R[j](0, i)));
        return c;
    };
    for (const auto& [key, st] : ch.states)
    {
        if (st.frames < minStateFrames(ch.frames)) continue;
        ChainStateDiagnostics sd;
        sd.antenna = key.first;
        sd.state = key.second;
        sd.frames = st.frames;
        sd.delay_s = st.frames ? st.delaySum_s / double(st.frames) : 0.0;
        sd.reference = key.second == referenceState[key.first];
        if (!sd.reference)
        {
            const Eigen::MatrixXcf ref = crossProducts(key.first, referenceState[key.first]);
            Eigen::MatrixXcf rel = crossProducts(key.first, key.second);
            rel = rel.cwiseProduct(ref.conjugate());
            const double slope = CsiPreprocessor::estimatePhaseSlope(rel, ch.layout->subcarriers);
            sd.deltaDelay_s = -slope / (2 * M_PI * kSubcarrierSpacingHz);
            std::complex<double> sum{0, 0};
            for (size_t j = 0; j < nSub; ++j)
                sum += std::complex<double>(rel(0, Eigen::Index(j))) *
                       std::polar(1.0, -slope * ch.layout->subcarriers[j]);
            sd.deltaPhase_rad = std::arg(sum);
        }
        states[key] = sd;
    }
    // A moving robot's multipath shifts a chain's measured delay by 1–2 ns at 80 MHz for a
    // stretch of frames, and the tracker opens a "state" for it; a jump is a step of a quarter
    // sample (3.1 ns at 80 MHz, 12.5 ns at 20 MHz; 3.0–3.3 ns and 11.9–13.1 ns measured). A
    // state less than three quarters of a step from its chain's reference, with the
    // reference's phase, is the reference itself: its frames join it, and the file keeps the
    // chain's delay.
    const double sameStateDelay_s =
        0.75 * 3.125e-9 * chainStateDelayScale(bandwidthOfSubcarriers(ch.layout->subcarriers));
    std::set<std::pair<unsigned, uint8_t>> merged;
    for (auto it = states.begin(); it != states.end();)
    {
        const auto& sd = it->second;
        const auto ref = states.find({sd.antenna, referenceState[sd.antenna]});
        if (sd.reference || ref == states.end() || std::abs(sd.deltaDelay_s) >= sameStateDelay_s ||
            std::abs(sd.deltaPhase_rad) >= kSameStatePhase_rad)
        {
            ++it;
            continue;
        }
        auto& r = ref->second;
        r.delay_s = (r.delay_s * double(r.frames) + sd.delay_s * double(sd.frames)) /
                    double(r.frames + sd.frames);
        r.frames += sd.frames;
        merged.insert(it->first);
        it = states.erase(it);
    }
    std::vector<Segment> segments;
    for (const auto& s : ch.segments)
    {
        // A state seen in a handful of frames is more likely a misread than a state: its
        // frames are left out rather than calibrated on their own.
        bool known = true;
        for (unsigned i = 1; i < s.chainState.size(); ++i)
            known =
                known && (states.count({i, s.chainState[i]}) || merged.count({i, s.chainState[i]}));
        if (known) segments.push_back(s);
    }
    if (!states.empty())
        for (auto& s : segments)
        {
            // R'(a, b) = d_a·R(a, b)·conj(d_b), d_i = e^{j(2π·k·Δf·Δd_i − Δψ_i)}.
            std::vector<double> dd(n, 0.0), dp(n, 0.0);
            for (unsigned i = 1; i < n && i < s.chainState.size(); ++i)
                if (const auto st = states.find({i, s.chainState[i]}); st != states.end())
                    dd[i] = st->second.deltaDelay_s, dp[i] = st->second.deltaPhase_rad;
            for (size_t j = 0; j < nSub; ++j)
            {
                Eigen::VectorXcd dj(n);
                for (unsigned i = 0; i < n; ++i)
                    dj[i] = std::polar(
                        1.0, 2 * M_PI * kSubcarrierSpacingHz * dd[i] * ch.layout->subcarriers[j] -
                                 dp[i]);
                s.R[j] = dj.asDiagonal() * s.R[j] * dj.conjugate().asDiagonal();
            }
        }
    for (const auto& [key, sd] : states) d.chainStates.push_back(sd);
    d.chainStateChanges = ch.stateChanges;
    d.unknownStateFrames = ch.unknownStateFrames;
    d.mergedChainStates = merged.size();

    d.frames = ch.frames;
    d.snapshots = ch.snapshots;
    d.segments = segments.size();
    d.duration_s = ch.tLast - ch.tFirst;

    // Pooled covariances and the coarse calibration: principal component per subcarrier.
    std::vector<Eigen::MatrixXcd> pooled(nSub, Eigen::MatrixXcd::Zero(n, n));
    for (const auto& s : segments)
        for (size_t j = 0; j < nSub; ++j) pooled[j] += s.R[j];
    out.coarsePhases_rad.assign(n, std::vector<double>(nSub, 0.0));
    std::vector<double> phi((n - 1) * nSub, 0.0);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXcd> eig;
    double shareSum = 0;
    for (size_t j = 0; j < nSub; ++j)
    {
        pooled[j] = hermitian(pooled[j]);
        eig.compute(pooled[j]);
        const Eigen::VectorXcd u0 = eig.eigenvectors().col(n - 1);  // ascending eigenvalues
        const double tr = pooled[j].trace().real();
        shareSum += tr > 0 ? eig.eigenvalues()[n - 1] / tr : 0;
        for (unsigned i = 1; i < n; ++i)
        {
            double p = std::arg(u0[i] * std::conj(u0[0]));
            // Unwrapped along the subcarriers: continuous curves, small LM steps.
            if (j > 0)
                p = out.coarsePhases_rad[i][j - 1] + wrapAngle(p - out.coarsePhases_rad[i][j - 1]);
            out.coarsePhases_rad[i][j] = p;
            phi[(i - 1) * nSub + j] = p;
        }
    }
    d.principalShare = shareSum / double(nSub);

    const auto coherence =
        [&](const std::vector<double>& ph, const std::vector<Eigen::MatrixXcd>& Rs)
    {
        double num = 0, den = 0;
        for (size_t j = 0; j < nSub; ++j)
        {
            const Eigen::VectorXcd v = unitWeights(ph, j, nSub, n);
            num += (v.adjoint() * Rs[j] * v)(0, 0).real();
            den += n * Rs[j].trace().real();
        }
        return den > 0 ? num / den : 0.0;
    };
    d.coarseResidual_rad = std::sqrt(-std::log(std::clamp(coherence(phi, pooled), 1e-12, 1.0)));

    // Levenberg–Marquardt refinement against each segment's orthogonal subspace.
    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    po.loss_function_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    // One parameter block per subcarrier (antennas 1..n−1; antenna 0 is the fixed reference).
    // `phi` is [antenna][subcarrier]: solve on a transposed copy with contiguous blocks.
    std::vector<double> blocks(nSub * (n - 1));
    for (size_t j = 0; j < nSub; ++j)
        for (unsigned i = 1; i < n; ++i) blocks[j * (n - 1) + (i - 1)] = phi[(i - 1) * nSub + j];
    size_t residualBlocks = 0;
    for (const auto& s : segments)
    {
        if (s.frames == 0) continue;
        const double norm = double(n) * double(s.frames);
        for (size_t j = 0; j < nSub; ++j)
        {
            const Eigen::MatrixXcd R = hermitian(s.R[j]);
            eig.compute(R);
            const Eigen::VectorXd lam = eig.eigenvalues();
            const double l0 = lam[n - 1];
            if (!(l0 > 0)) continue;
            Eigen::MatrixXcd L(n - 1, n);
            for (unsigned q = 0; q + 1 < n; ++q)
                L.row(q) = std::sqrt(std::max(l0 - lam[q], 0.0) / norm) *
                           eig.eigenvectors().col(q).adjoint();
            ceres::LossFunction* loss = nullptr;
            if (opts_.robustScale > 0)
                loss = new ceres::ScaledLoss(
                    new ceres::CauchyLoss(opts_.robustScale), double(s.frames),
                    ceres::TAKE_OWNERSHIP);
            else
                L *= std::sqrt(double(s.frames));
            problem.AddResidualBlock(
                new OrthogonalSubspaceCost(std::move(L)), loss, &blocks[j * (n - 1)]);
            ++residualBlocks;
        }
    }
    if (residualBlocks > 0)
    {
        ceres::Solver::Options so;
        so.minimizer_type = ceres::TRUST_REGION;
        so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
        // Subcarriers don't share parameters: the normal equations are block diagonal.
        so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
        if (!ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE))
            so.sparse_linear_algebra_library_type = ceres::EIGEN_SPARSE;
        so.max_num_iterations = int(opts_.maxIterations);
        so.num_threads = 1;
        so.logging_type = ceres::SILENT;
        so.function_tolerance = 1e-9;
        ceres::Solver::Summary summary;
        ceres::Solve(so, &problem, &summary);
        d.iterations = unsigned(summary.iterations.size());
        d.initialCost = summary.initial_cost;
        d.finalCost = summary.final_cost;
        d.solverReport = summary.BriefReport();
        for (size_t j = 0; j < nSub; ++j)
            for (unsigned i = 1; i < n; ++i)
                phi[(i - 1) * nSub + j] = blocks[j * (n - 1) + (i - 1)];
    }
    d.residual_rad = std::sqrt(-std::log(std::clamp(coherence(phi, pooled), 1e-12, 1.0)));

    // Share of frames in segments the calibrated line of sight explains well.
    double losFrames = 0, allFrames = 0;
    for (const auto& s : segments)
    {
        double num = 0, den = 0;
        for (size_t j = 0; j < nSub; ++j)
        {
            const Eigen::MatrixXcd R = hermitian(s.R[j]);
            const Eigen::VectorXcd v = unitWeights(phi, j, nSub, n);
            num += (v.adjoint() * R * v)(0, 0).real();
            den += n * R.trace().real();
        }
        allFrames += double(s.frames);
        if (den > 0 && num / den >= opts_.losCoherence) losFrames += double(s.frames);
    }
    d.losShare = allFrames > 0 ? losFrames / allFrames : 0;

    // The calibration file.
    PhaseCalibration& c = out.calibration;
    c.device = array_.name;
    c.chanspec = ch.layout->chanspec;
    c.date = isoNow();
    c.framesUsed = ch.frames;
    c.residual_rad = d.residual_rad;
    c.method = drive ? "wifi-calibrate drive (per-subcarrier PCA + Ceres LM, Cauchy loss)"
                     : "wifi-calibrate splitter (per-subcarrier PCA + Ceres LM)";
    c.subbandSignCorrected = true;
    c.subcarriers = ch.layout->subcarriers;
    c.phases_rad.assign(n, std::vector<double>(nSub, 0.0));
    for (unsigned i = 1; i < n; ++i)
        for (size_t j = 0; j < nSub; ++j) c.phases_rad[i][j] = wrapAngle(phi[(i - 1) * nSub + j]);
    if (opts_.estimateGains && ch.antennaPower[0] > 0)
    {
        c.gains_dB.resize(n);
        for (unsigned i = 0; i < n; ++i)
            c.gains_dB[i] =
                10 * std::log10(std::max(ch.antennaPower[i], 1e-30) / ch.antennaPower[0]);
    }
    // States are ~1/(4·bandwidth) apart (3 ns at 80 MHz, 12.5 ns at 20 MHz): so is the
    // tolerance a frame's delay is matched to them with.
    c.chainStateTolerance_s *= chainStateDelayScale(c.chanspec.bandwidthMHz);
    for (const auto& sd : d.chainStates)
    {
        ChainStateCalibration st;
        st.antenna = sd.antenna;
        st.state = sd.state;
        st.delay_s = sd.delay_s;
        st.deltaDelay_s = sd.deltaDelay_s;
        st.deltaPhase_rad = sd.deltaPhase_rad;
        st.frames = sd.frames;
        c.chainStates.push_back(st);
    }
    c.validate("calibration of " + cs.asString());

    // Observability of the drive.
    auto& w = out.warnings;
    if (ch.frames < opts_.minFrames)
        w.push_back(
            "only " + std::to_string(ch.frames) + " usable frames (need " +
            std::to_string(opts_.minFrames) + "): record longer, or check the MAC and RSSI gate");
    // A static splitter recording needs frames, not time: nothing moves.
    if (drive && d.duration_s < opts_.minDuration_s)
        w.push_back(
            "the recording lasts only " + fmt(d.duration_s) + " s (need " +
            fmt(opts_.minDuration_s, 0) + " s)");
    if (drive && !ch.foldedAoa.empty())
    {
        const auto [lo, hi] = array_.searchInterval();
        const double bin = opts_.bearingBin_deg * M_PI / 180;
        const size_t nBins = size_t(std::ceil((hi - lo) / bin));
        std::vector<size_t> hist(nBins, 0);
        for (float a : ch.foldedAoa)
        {
            const double rel = wrapAngle(double(a) - lo);  // in [0, hi − lo) up to wrapping
            const double pos = rel < 0 ? rel + 2 * M_PI : rel;
            hist[std::min(nBins - 1, size_t(pos / bin))]++;
        }
        d.bearingBins = 0;
        for (size_t h : hist)
            if (double(h) >= opts_.minBinShare * double(ch.foldedAoa.size())) ++d.bearingBins;
        std::vector<double> deg;
        deg.reserve(ch.foldedAoa.size());
        for (float a : ch.foldedAoa)
        {
            const double rel = wrapAngle(double(a) - lo);
            deg.push_back((rel < 0 ? rel + 2 * M_PI : rel) * 180 / M_PI);
        }
        d.bearingSpan_deg = quantile(deg, 0.95) - quantile(deg, 0.05);
        d.medianDistance_m =
            quantile(std::vector<double>(ch.distance.begin(), ch.distance.end()), 0.5);
        if (d.bearingBins < opts_.minBearingBins)
            w.push_back(
                "the transmitter was seen from only " + std::to_string(d.bearingBins) +
                " distinct bearings (" + fmt(opts_.bearingBin_deg, 0) + "° bins, need " +
                std::to_string(opts_.minBearingBins) +
                "): drive around it and turn the robot so reflections average out");
        if (d.medianDistance_m > opts_.maxMedianDistance_m)
            w.push_back(
                "the transmitter was a median " + fmt(d.medianDistance_m) + " m away (limit " +
                fmt(opts_.maxMedianDistance_m) +
                " m): drive within ~5 m of it so the line of sight dominates");
    }
    if (d.losShare < opts_.minLosShare)
        w.push_back(
            drive ? "the calibrated line of sight explains the CSI in only " +
                        fmt(100 * d.losShare, 0) + " % of the drive (need " +
                        fmt(100 * opts_.minLosShare, 0) +
                        " %): line of sight mostly blocked, or wrong transmitter position/poses"
                  : "the antennas see a common signal in only " + fmt(100 * d.losShare, 0) +
                        " % of the recording: is the splitter connected to every antenna?");
    d.solveTime_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    if (drive && !ch.kept.empty())
    {
        out.bearingErrorBefore_deg = bearingErrors_deg(ch.kept, array_, nullptr);
        std::vector<CalibrationFrame> corrected;
        corrected.reserve(ch.kept.size());
        for (const auto& f : ch.kept)
        {
            corrected.push_back(f);
            if (!removeChainStates(c, corrected.back())) corrected.pop_back();
        }
        out.bearingErrorAfter_deg = bearingErrors_deg(corrected, array_, &c);
        if (!out.bearingErrorAfter_deg.empty() &&
            quantile(out.bearingErrorAfter_deg, 0.9) > opts_.maxP90Error_deg)
            w.push_back(
                "the calibration does not explain the drive: 90 % of its frames' bearings are "
                "within " +
                fmt(quantile(out.bearingErrorAfter_deg, 0.9)) + "° only (limit " +
                fmt(opts_.maxP90Error_deg, 0) +
                "°): wrong transmitter position or poses, or the receive chains changed state "
                "in a way the drive could not separate");
    }
    return out;
}

}  // namespace mrpt_wifi::calib
