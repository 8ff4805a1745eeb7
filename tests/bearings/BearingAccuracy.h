/* mrpt_wifi — accuracy evaluation of the bearing estimators against the simulator's ground
 * truth. Shared by the accuracy tests and the bearing-accuracy program. */
#pragma once

#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/obs/bearing/BearingEstimator.h>
#include <mrpt_wifi/obs/bearing/BearingProcessor.h>
#include <mrpt_wifi/sim/RandomRoom.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace mrpt_wifi::test
{
enum class Environment
{
    LineOfSight,  //!< the scenario's room without reflections, scatterers or obstacles
    Moderate,     //!< the scenario as written
    Strong        //!< walls |Γ| = 0.7, scatterers 4× stronger
};
inline const char* toString(Environment e)
{
    return e == Environment::LineOfSight ? "LoS only"
           : e == Environment::Moderate  ? "moderate multipath"
                                         : "strong multipath";
}

struct AccuracyCase
{
    std::string scenarioFile;
    Environment environment = Environment::Moderate;
    double snr_dB = 20;
    bool calibrated = true;
    unsigned estimates = 150;   //!< spread evenly over the scenario's duration
    unsigned windowFrames = 8;  //!< consecutive frames synthesised per estimate
    std::string rxArrayFile;    //!< "" = the scenario's receiver array
};

/** Frames and truth of one case, made once and shared by all estimators. */
struct AccuracyDataset
{
    AntennaArray rx;
    std::map<MacAddress, AntennaArray> txArrays;
    std::optional<PhaseCalibration> calibration;
    std::vector<std::vector<CObservationWiFiCSI>> windows;  //!< oldest first
    std::vector<sim::FrameTruth> truth;                     //!< of each window's last frame
    double snr_dB = 0;
};

inline AntennaArray fromSimArray(const sim::AntennaArray& a)
{
    AntennaArray out;
    out.name = a.name;
    out.elements = a.elements;
    out.sourcePath = a.sourcePath;
    return out;
}

/** The simulator's true per-chain responses on a channel: what a perfect calibration recovers. */
inline PhaseCalibration truthCalibration(
    const sim::Simulator& simulator, const AntennaArray& rx, const Chanspec& cs)
{
    PhaseCalibration cal;
    cal.device = rx.name;
    cal.chanspec = cs;
    cal.method = "simulator ground truth (scenario " + simulator.scenario().name + ", seed " +
                 std::to_string(simulator.scenario().seed) + ")";
    cal.subcarriers = dataSubcarriers(cs.bandwidthMHz);
    for (size_t i = 0; i < rx.size(); ++i)
    {
        const auto& ch = simulator.hardware().chain(cs, unsigned(i));
        // Chains 1.. hold in jump state 0, which may have a delay of its own (listed states).
        const auto& hw = simulator.hardware();
        const double stateZero_s = i > 0 && hw.spec().antennaJumps ? hw.jumpStateDelay_s(0) : 0.0;
        std::vector<double> row;
        for (int k : cal.subcarriers)
            row.push_back(wrapAngle(
                ch.phase_rad(k, cs.nfft()) -
                2 * M_PI *
                    std::fmod(
                        (hw.spec().jumpBaseband ? k * kSubcarrierSpacingHz
                                                : subcarrierFrequencyHz(cs, k)) *
                            stateZero_s,
                        1.0)));
        cal.phases_rad.push_back(row);
        cal.gains_dB.push_back(ch.gain_dB);
    }
    // Jump states: state s of chain i adds a delay τ_s (phase −2π·f_k·τ_s) and its own phase;
    // relative to state 0 that is deltaDelay = τ_s − τ_0, deltaPhase = −2π·f_c·(τ_s − τ_0) + own
    // phase. The centre a frame is classified by is the delay the chain's response itself
    // implies (its phase slope relative to chain 0, state 0 included) plus τ_s − τ_0.
    const auto& hw = simulator.hardware();
    if (hw.spec().antennaJumps)
    {
        const double fc = cs.centerFrequencyHz();
        for (size_t i = 1; i < rx.size() && i < hw.chains(); ++i)
        {
            double sk = 0, skk = 0, sp = 0, skp = 0;
            const double n = double(cal.subcarriers.size());
            for (size_t j = 0; j < cal.subcarriers.size(); ++j)
            {
                const double k = cal.subcarriers[j];
                const double p = hw.chain(cs, unsigned(i)).phase_rad(int(k), cs.nfft()) -
                                 hw.chain(cs, 0).phase_rad(int(k), cs.nfft());
                sk += k, skk += k * k, sp += p, skp += k * p;
            }
            const double slope = (n * skp - sk * sp) / (n * skk - sk * sk);
            const double ownDelay = -slope / (2 * M_PI * kSubcarrierSpacingHz);
            for (unsigned st = 0; st < hw.spec().jumpStates; ++st)
            {
                ChainStateCalibration c;
                c.antenna = unsigned(i);
                c.state = uint8_t(st);
                c.deltaDelay_s = hw.jumpStateDelay_s(uint8_t(st)) - hw.jumpStateDelay_s(0);
                c.delay_s = ownDelay + hw.jumpStateDelay_s(uint8_t(st));
                c.deltaPhase_rad = wrapAngle(
                    (hw.spec().jumpBaseband ? 0.0
                                            : -2 * M_PI * std::fmod(fc * c.deltaDelay_s, 1.0)) +
                    hw.jumpStatePhase_rad(unsigned(i), uint8_t(st)) -
                    hw.jumpStatePhase_rad(unsigned(i), 0));
                cal.chainStates.push_back(c);
            }
        }
    }
    return cal;
}

inline AccuracyDataset makeDataset(const AccuracyCase& c, sim::Scenario sc);

inline AccuracyDataset makeDataset(const AccuracyCase& c)
{
    return makeDataset(c, sim::Scenario::fromYamlFile(c.scenarioFile));
}

/** A case on random room `seed` (mrpt_wifi::sim::randomRoomScenario). */
inline AccuracyDataset makeRandomRoomDataset(
    const AccuracyCase& c, uint32_t seed, const std::string& receiver = "rt-ac86u")
{
    sim::RandomRoomOptions ro;
    ro.arraysDir = std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays";
    ro.receiver = receiver;
    return makeDataset(c, sim::randomRoomScenario(seed, ro));
}

/** The case's environment, SNR and receive array applied to a scenario; transmit chains
 *  without phase or gain offsets (as if calibrated). */
inline void applyCase(const AccuracyCase& c, sim::Scenario& sc)
{
    if (!c.rxArrayFile.empty()) sc.receiver.array = sim::AntennaArray::fromYamlFile(c.rxArrayFile);
    sc.impairments.fixedSnr_dB = c.snr_dB;
    // The estimators' AoD with calibrated transmit chains (as the receive side is calibrated
    // with the truth below); the transmit-chain calibration itself: tests/calib/test_tx_calib.
    sc.impairments.txChainPhaseOffsets = false;
    sc.impairments.txChainGainSigma_dB = 0;
    if (c.environment == Environment::LineOfSight)
    {
        sc.propagation.maxReflectionOrder = 0;
        sc.scatterers.clear();
        sc.obstacles.clear();
        sc.receiver.bodyShadow.attenuation_dB = 0;
    }
    else if (c.environment == Environment::Strong)
    {
        for (auto& w : sc.walls) w.reflection = std::polar(0.7, M_PI);
        for (auto& s : sc.scatterers) s.radarCrossSection_m2 *= 4;
    }
}

inline AccuracyDataset makeDataset(const AccuracyCase& c, sim::Scenario sc)
{
    applyCase(c, sc);
    sim::Simulator simulator(sc);

    AccuracyDataset d;
    d.snr_dB = c.snr_dB;
    d.rx = fromSimArray(sc.receiver.array);
    for (const auto& t : sc.transmitters) d.txArrays[t.mac] = fromSimArray(t.array);
    if (c.calibrated)
        d.calibration = truthCalibration(simulator, d.rx, sc.transmitters.front().chanspec);
    const size_t nTx = sc.transmitters.size();
    for (unsigned e = 0; e < c.estimates; ++e)
    {
        const size_t tx = e % nTx;
        const double t = (e + 0.5) / c.estimates * (sc.duration_s - 1.0);
        const uint64_t first = simulator.firstFrameAtOrAfter(tx, t);
        std::vector<CObservationWiFiCSI> w(c.windowFrames);
        sim::FrameTruth truth;
        for (unsigned n = 0; n < c.windowFrames; ++n)
            simulator.synthesizeFrame(tx, first + n, w[n], truth);
        d.windows.push_back(std::move(w));
        d.truth.push_back(truth);
    }
    return d;
}

struct AccuracyStats
{
    std::string algorithm;
    size_t count = 0;
    double median_deg = NAN, p90_deg = NAN;
    double crbMedian_deg = NAN;
    double errorOverCrbRms = NAN;  //!< √mean((error / CRB)²)
    /** The same within ±60° of broadside: beyond, the rt-ac86u's 26 mm spacing (> λ/2 at
     *  5.8 GHz) aliases one endfire onto the other and the local bound does not apply. */
    double errorOverCrbRmsCentral = NAN;
    double centralMedian_deg = NAN;
    size_t centralCount = 0;
    size_t aodCount = 0;
    double aodMedian_deg = NAN, aodP90_deg = NAN;
    double meanQuality = NAN;
    double meanStd_deg = NAN;       //!< reported σ, to compare with the errors
    double withinThreeSigma = NAN;  //!< fraction of estimates with error ≤ 3 × reported σ
};

inline double percentile(std::vector<double> v, double p)
{
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    const double pos = p * double(v.size() - 1);
    const size_t i = size_t(pos);
    return i + 1 < v.size() ? v[i] + (pos - double(i)) * (v[i + 1] - v[i]) : v[i];
}

/** What forEachEstimate() hands over per estimate. */
struct EstimateOnWindow
{
    const bearing::BearingResult& result;
    const std::vector<const CleanCsi*>& frames;  //!< the preprocessed window it used
    size_t window;                               //!< index into the dataset's windows / truth
    double aoaError_rad;  //!< to the nearer reported candidate (mirror of linear arrays)
    double streams;       //!< transmit streams over the window (for the CRB)
};

/** Runs an estimator over every window of a dataset (each preprocessed as the bearing chain
 *  would) and calls `use` per estimate it made; returns the number of windows it produced
 *  nothing for. Linear arrays: the error is to the nearer of the two reported mirror
 *  candidates (resolving the mirror needs motion or a 2-D array, not this estimator). */
template <class Use>
size_t forEachEstimate(
    const AccuracyDataset& d, const std::string& algo, const mrpt::containers::yaml& params,
    Use&& use)
{
    auto est = bearing::createEstimator(algo, params);
    CsiPreprocessor pre(
        {}, d.rx,
        d.calibration ? CalibrationStore::fromCalibration(*d.calibration) : CalibrationStore());
    std::vector<CleanCsi> clean;
    std::vector<const CleanCsi*> ptrs;
    bearing::EstimatorContext ctx;
    ctx.rxArray = &d.rx;
    ctx.txArrayOf = [&](const MacAddress& m) -> const AntennaArray*
    {
        const auto it = d.txArrays.find(m);
        return it == d.txArrays.end() ? nullptr : &it->second;
    };
    size_t missing = 0;
    for (size_t e = 0; e < d.windows.size(); ++e)
    {
        const auto& w = d.windows[e];
        const size_t n = std::min<size_t>(est->framesWanted(), w.size());
        clean.resize(n);
        ptrs.clear();
        for (size_t k = 0; k < n; ++k)
        {
            if (pre.process(w[w.size() - n + k], clean[k]) != RejectReason::Accepted) continue;
            ptrs.push_back(&clean[k]);
        }
        bearing::BearingResult r;
        if (ptrs.empty() || !est->estimate(ptrs, ctx, r) || !r.valid)
        {
            ++missing;
            continue;
        }
        const auto& truth = d.truth[e];
        double err = angleDistance(r.aoa_rad, truth.aoa_rad);
        if (r.aoaAmbiguous) err = std::min(err, angleDistance(r.aoaMirror_rad, truth.aoa_rad));
        double streams = 0;
        for (const auto* p : ptrs) streams += p->nTx;
        use(EstimateOnWindow{r, ptrs, e, err, streams});
    }
    return missing;
}

/** Runs one estimator on a dataset. Linear arrays: error to the nearer of the two reported
 *  mirror candidates (resolving the mirror needs motion or a 2-D array, not this estimator). */
inline AccuracyStats evaluate(
    const AccuracyDataset& d, const std::string& algo,
    const mrpt::containers::yaml& params = mrpt::containers::yaml())
{
    size_t inside = 0;
    std::vector<double> errors, crbs, ratios, centralRatios, centralErrors, aodErrors, quality,
        stds;
    forEachEstimate(
        d, algo, params,
        [&](const EstimateOnWindow& x)
        {
            const auto& r = x.result;
            const auto& truth = d.truth[x.window];
            const double err = x.aoaError_rad;
            const double streams = x.streams;
            const auto& layout = *x.frames.back()->layout;
            const double crb = d.rx.aoaCramerRaoBound(
                truth.aoa_rad, layout.frequencies_Hz, std::pow(10.0, d.snr_dB / 10), streams);
            errors.push_back(err * 180 / M_PI);
            crbs.push_back(crb * 180 / M_PI);
            ratios.push_back(err / crb);
            const double offBroadside = std::min(
                angleDistance(truth.aoa_rad, d.rx.broadside()),
                angleDistance(d.rx.mirrorOf(truth.aoa_rad), d.rx.broadside()));
            if (offBroadside <= M_PI / 3)
            {
                centralRatios.push_back(err / crb);
                centralErrors.push_back(err * 180 / M_PI);
            }
            quality.push_back(r.quality);
            stds.push_back(r.aoaStd_rad * 180 / M_PI);
            if (err <= 3 * r.aoaStd_rad) ++inside;
            if (r.hasAod)
            {
                double ae = angleDistance(r.aod_rad, truth.aod_rad);
                if (r.aodAmbiguous)
                    ae = std::min(ae, angleDistance(r.aodMirror_rad, truth.aod_rad));
                aodErrors.push_back(ae * 180 / M_PI);
            }
        });
    AccuracyStats s;
    s.algorithm = algo;
    s.count = errors.size();
    s.median_deg = percentile(errors, 0.5);
    s.p90_deg = percentile(errors, 0.9);
    s.crbMedian_deg = percentile(crbs, 0.5);
    double sq = 0;
    for (double r : ratios) sq += r * r;
    s.errorOverCrbRms = ratios.empty() ? NAN : std::sqrt(sq / double(ratios.size()));
    double csq = 0;
    for (double r : centralRatios) csq += r * r;
    s.errorOverCrbRmsCentral =
        centralRatios.empty() ? NAN : std::sqrt(csq / double(centralRatios.size()));
    s.centralMedian_deg = percentile(centralErrors, 0.5);
    s.centralCount = centralErrors.size();
    s.aodCount = aodErrors.size();
    s.aodMedian_deg = percentile(aodErrors, 0.5);
    s.aodP90_deg = percentile(aodErrors, 0.9);
    double qs = 0, ss = 0;
    for (double q : quality) qs += q;
    for (double x : stds) ss += x;
    s.meanQuality = quality.empty() ? NAN : qs / double(quality.size());
    s.meanStd_deg = stds.empty() ? NAN : ss / double(stds.size());
    s.withinThreeSigma = errors.empty() ? NAN : double(inside) / double(errors.size());
    return s;
}

/** One estimate against the truth. */
struct ErrorRecord
{
    double error_deg = NAN;  //!< to the nearer reported candidate
    double std_deg = NAN;    //!< reported σ
    double crb_deg = NAN;
    bool central = false;  //!< truth within 75° of broadside
    // Whole-stream records only (streamErrors):
    double time_s = NAN, truth_deg = NAN, estimate_deg = NAN;
    int transmitter = -1;
    int trackChoice = -1;  //!< candidate the tracker chose (0: the estimator's)
    double trackSupport = NAN;
    double yaw_deg = NAN;  //!< odometry yaw the processor had at the estimate
    double quality = NAN;
    /** Whole-stream records: the directions the estimator weighed besides its own (before the
     *  tracker), each with its folded error to the truth [deg], and its weight evidence. */
    struct Candidate
    {
        double error_deg, weight, relativePower, delayAfter_ns;
        bool kept;
    };
    std::vector<Candidate> candidates;
    /** The folded error of the emitted bearing's nearest alternative (NaN: none) [deg]. */
    double alternativeError_deg = NAN;
};

/** Runs an estimator over a dataset and appends one record per estimate it made; returns the
 *  number of windows it produced nothing for. */
inline size_t collectErrors(
    const AccuracyDataset& d, const std::string& algo, std::vector<ErrorRecord>& out,
    const mrpt::containers::yaml& params = mrpt::containers::yaml())
{
    return forEachEstimate(
        d, algo, params,
        [&](const EstimateOnWindow& x)
        {
            const auto& truth = d.truth[x.window];
            ErrorRecord rec;
            rec.error_deg = x.aoaError_rad * 180 / M_PI;
            rec.std_deg = x.result.aoaStd_rad * 180 / M_PI;
            rec.crb_deg = d.rx.aoaCramerRaoBound(
                              truth.aoa_rad, x.frames.back()->layout->frequencies_Hz,
                              std::pow(10.0, d.snr_dB / 10), x.streams) *
                          180 / M_PI;
            const double offBroadside = std::min(
                angleDistance(truth.aoa_rad, d.rx.broadside()),
                angleDistance(d.rx.mirrorOf(truth.aoa_rad), d.rx.broadside()));
            rec.central = offBroadside <= 75 * M_PI / 180;
            out.push_back(rec);
        });
}

/** Where a whole-stream evaluation takes the robot's motion from. */
enum class StreamPoses
{
    None,             //!< no odometry at all (as the live sensor without an odometry source)
    Truth,            //!< the true robot poses
    Odometry,         //!< the scenario's wheel odometry (noisy)
    DriftingOdometry  //!< wheel odometry with 2 % scale errors and 1°/m heading drift
};
inline const char* toString(StreamPoses p)
{
    return p == StreamPoses::None       ? "no odometry"
           : p == StreamPoses::Truth    ? "true poses"
           : p == StreamPoses::Odometry ? "odometry poses"
                                        : "drifting odometry poses";
}

struct StreamCase
{
    AccuracyCase base;  //!< environment, SNR, receive array (estimates/windowFrames unused)
    StreamPoses poses = StreamPoses::Truth;
    double duration_s = 30;  //!< of the scenario streamed, from its start
    unsigned stride = 8;     //!< one estimate per transmitter every `stride` frames
    /** BearingProcessor::Options::tracking (nullopt: the processor's default). */
    std::optional<bool> tracking;
    /** The 4366c0's jump states switched on at this rate [Hz] (0: off), three states 3 ns
     *  apart, each with its own phase; the truth calibration holds every state. */
    double jumpRate_Hz = 0;
};

/** Whole-stream evaluation: one random room's odometry and CSI in time order through one
 *  BearingProcessor per algorithm (as csi-bearings runs them), every estimate against the
 *  truth of its newest frame; appends one record per estimate to out[algo]. Returns the number
 *  of frames streamed. */
inline size_t streamErrors(
    const StreamCase& c, uint32_t seed, const std::vector<std::string>& algos,
    const mrpt::containers::yaml& params, std::map<std::string, std::vector<ErrorRecord>>& out)
{
    sim::RandomRoomOptions ro;
    ro.arraysDir = std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays";
    ro.duration_s = std::max(c.duration_s, 1.0);
    sim::Scenario sc = sim::randomRoomScenario(seed, ro);
    applyCase(c.base, sc);
    if (c.poses == StreamPoses::DriftingOdometry)
    {
        sc.odometry.scaleError = 0.02;
        sc.odometry.yawScaleError = 0.02;
        sc.odometry.yawDrift_rad_per_m = 1.0 * M_PI / 180;
    }
    if (c.jumpRate_Hz > 0)
    {
        sc.impairments.antennaJumps = true;
        sc.impairments.jumpStates = 3;
        sc.impairments.jumpStep_s = 3e-9;
        sc.impairments.jumpRate_Hz = c.jumpRate_Hz;
        sc.impairments.jumpStatePhase = true;
    }
    sim::Simulator simulator(sc);
    const AntennaArray rx = fromSimArray(sc.receiver.array);
    const PhaseCalibration cal = truthCalibration(simulator, rx, sc.transmitters.front().chanspec);
    std::vector<std::unique_ptr<bearing::BearingProcessor>> procs;
    for (const auto& a : algos)
    {
        bearing::BearingProcessor::Options o;
        o.stride = c.stride;
        o.tracking = c.tracking;
        PreprocessOptions po;
        po.trackChainStates = c.jumpRate_Hz > 0;
        procs.push_back(std::make_unique<bearing::BearingProcessor>(
            CsiPreprocessor(po, rx, CalibrationStore::fromCalibration(cal)),
            bearing::createEstimator(a, params), o));
        for (const auto& t : sc.transmitters)
            procs.back()->setTransmitterArray(t.mac, fromSimArray(t.array));
    }
    const double snr = std::pow(10.0, c.base.snr_dB / 10);
    sim::SimEvent ev;
    size_t frames = 0;
    while (simulator.next(ev))
    {
        if (ev.kind == sim::SimEvent::Kind::Odometry)
        {
            if (c.poses == StreamPoses::None) continue;
            const auto pose =
                c.poses == StreamPoses::Truth ? ev.truePose : ev.odometry->odometry.asTPose();
            for (auto& p : procs) p->addOdometry(ev.odometry->timestamp, pose);
            continue;
        }
        ++frames;
        const sim::FrameTruth& truth = ev.frame;
        for (size_t k = 0; k < procs.size(); ++k)
        {
            const auto b = procs[k]->process(*ev.csi);
            if (!b) continue;
            double err = angleDistance(b->aoa_rad, truth.aoa_rad);
            if (b->aoaAmbiguous)
                err = std::min(err, angleDistance(b->aoaMirror_rad, truth.aoa_rad));
            double streams = 0;
            for (const auto* f : procs[k]->lastWindow()) streams += f->nTx;
            ErrorRecord rec;
            rec.error_deg = err * 180 / M_PI;
            rec.std_deg = b->aoaStd_rad * 180 / M_PI;
            rec.crb_deg =
                rx.aoaCramerRaoBound(
                    truth.aoa_rad, procs[k]->lastFrame()->layout->frequencies_Hz, snr, streams) *
                180 / M_PI;
            const double offBroadside = std::min(
                angleDistance(truth.aoa_rad, rx.broadside()),
                angleDistance(rx.mirrorOf(truth.aoa_rad), rx.broadside()));
            rec.central = offBroadside <= 75 * M_PI / 180;
            rec.time_s = truth.time_s;
            rec.transmitter = int(truth.transmitterIndex);
            rec.truth_deg = truth.aoa_rad * 180 / M_PI;
            rec.estimate_deg = b->aoa_rad * 180 / M_PI;
            rec.quality = b->quality;
            const auto folded = [&](double a)
            {
                double e = angleDistance(a, truth.aoa_rad);
                if (b->aoaAmbiguous) e = std::min(e, angleDistance(rx.mirrorOf(a), truth.aoa_rad));
                return e * 180 / M_PI;
            };
            for (const auto& a : b->aoaAlternatives())
                rec.alternativeError_deg =
                    std::isnan(rec.alternativeError_deg)
                        ? folded(a.aoa_rad)
                        : std::min(rec.alternativeError_deg, folded(a.aoa_rad));
            const auto& res = procs[k]->lastResult();
            for (const auto& a : res.aoaCandidates)
            {
                bool kept = false;
                for (const auto& e : res.aoaAlternatives())
                    kept = kept || std::abs(e.aoa_rad - a.aoa_rad) < 1e-12;
                rec.candidates.push_back(
                    {folded(a.aoa_rad), a.weight, a.relativePower, a.delayAfter_s * 1e9, kept});
            }
            if (const auto od = procs[k]->odometryAt(ev.csi->timestamp); od)
                rec.yaw_deg = od->phi * 180 / M_PI;
            if (procs[k]->tracking())
            {
                rec.trackChoice = int(procs[k]->lastTrackDecision().chosen);
                rec.trackSupport = procs[k]->lastTrackDecision().support;
            }
            out[algos[k]].push_back(rec);
        }
    }
    return frames;
}

/** The issue-10 figures over many rooms. */
struct RoomStats
{
    size_t count = 0, centralCount = 0;
    double centralMedian_deg = NAN, centralP90_deg = NAN, centralBeyond30 = NAN;
    double median_deg = NAN, p90_deg = NAN, beyond30 = NAN;
    double withinTwoSigma = NAN, withinThreeSigma = NAN;
    double crbMedian_deg = NAN, meanStd_deg = NAN;
    double medianStd_deg = NAN;  //!< reported σ, median over the estimates
    double centralMedianStd_deg = NAN;
};

inline RoomStats summarize(const std::vector<ErrorRecord>& recs)
{
    RoomStats s;
    std::vector<double> all, central, crb, sigmas, centralSigmas;
    size_t beyond = 0, cBeyond = 0, in2 = 0, in3 = 0;
    double stdSum = 0;
    for (const auto& r : recs)
    {
        all.push_back(r.error_deg);
        crb.push_back(r.crb_deg);
        stdSum += r.std_deg;
        sigmas.push_back(r.std_deg);
        if (r.central) centralSigmas.push_back(r.std_deg);
        beyond += r.error_deg > 30;
        in2 += r.error_deg <= 2 * r.std_deg;
        in3 += r.error_deg <= 3 * r.std_deg;
        if (!r.central) continue;
        central.push_back(r.error_deg);
        cBeyond += r.error_deg > 30;
    }
    s.count = all.size();
    s.centralCount = central.size();
    if (all.empty()) return s;
    s.median_deg = percentile(all, 0.5);
    s.p90_deg = percentile(all, 0.9);
    s.beyond30 = double(beyond) / double(all.size());
    s.centralMedian_deg = percentile(central, 0.5);
    s.centralP90_deg = percentile(central, 0.9);
    s.centralBeyond30 = central.empty() ? NAN : double(cBeyond) / double(central.size());
    s.withinTwoSigma = double(in2) / double(all.size());
    s.withinThreeSigma = double(in3) / double(all.size());
    s.crbMedian_deg = percentile(crb, 0.5);
    s.meanStd_deg = stdSum / double(all.size());
    s.medianStd_deg = percentile(sigmas, 0.5);
    s.centralMedianStd_deg = percentile(centralSigmas, 0.5);
    return s;
}

/** Seeds of the rooms: `count` consecutive seeds from the development or evaluation set. */
inline std::vector<uint32_t> roomSeeds(bool evaluation, unsigned count, unsigned offset = 0)
{
    std::vector<uint32_t> s;
    const uint32_t first = (evaluation ? sim::kFirstEvaluationSeed : 1u) + offset;
    for (unsigned i = 0; i < count; ++i) s.push_back(first + i);
    return s;
}

inline std::string scenarioPath(const std::string& name)
{
    return std::string(MRPT_WIFI_SOURCE_DIR) + "/share/scenarios/" + name + ".yaml";
}
inline std::string arrayPath(const std::string& name)
{
    return std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/" + name + ".yaml";
}

}  // namespace mrpt_wifi::test
