/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/math/wrap2pi.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt_wifi/obs/bearing/BearingProcessor.h>

#include <algorithm>
#include <cmath>

#include "BearingMath.h"

namespace mrpt_wifi::bearing
{
/** Workspace of findCandidates(): the wideband Bartlett spectrum of a window. */
struct BearingProcessor::CandidateScan
{
    const SubcarrierLayout* layout = nullptr;
    unsigned nRx = 0;
    AntennaArray rx;
    detail::AngleGrid grid;
    std::vector<double> gf, gc;
    detail::QuadraticFormGrid qf;
    std::vector<Eigen::MatrixXcd> R;
    Eigen::VectorXd spec;
};

namespace
{
/** A synthetic aperture needs each frame's absolute phase (the forward × reverse product
 *  carries the propagation phase) and the received amplitudes (its weights). */
CsiPreprocessor forEstimator(CsiPreprocessor pre, const BearingEstimator* est)
{
    if (!est || !est->syntheticAperture()) return pre;
    PreprocessOptions o = pre.options();
    if (!o.removeSamplingTimeOffset && !o.normalizePower && o.acceptSingleAntenna) return pre;
    o.removeSamplingTimeOffset = false;
    o.normalizePower = false;
    o.acceptSingleAntenna = true;
    return CsiPreprocessor(o, pre.rxArray(), pre.calibration());
}

BearingProcessor::Options forEstimator(BearingProcessor::Options o, const BearingEstimator* est)
{
    if (!est || !est->syntheticAperture()) return o;
    o.windowCapacity = std::max(o.windowCapacity, est->framesWanted());
    o.windowMaxAge_s = std::max(o.windowMaxAge_s, est->windowSpan_s());
    o.odometryHistory_s = std::max(o.odometryHistory_s, est->windowSpan_s() + 1.0);
    o.tracking = false;  // one estimate per aperture: nothing for a track to choose between
    return o;
}
}  // namespace

BearingProcessor::BearingProcessor(
    CsiPreprocessor preprocessor, std::unique_ptr<BearingEstimator> estimator, Options options)
    : pre_(forEstimator(std::move(preprocessor), estimator.get())),
      est_(std::move(estimator)),
      opts_(forEstimator(std::move(options), est_.get())),
      windows_(
          std::max(opts_.windowCapacity, est_ ? est_->framesWanted() : 1), opts_.windowMaxAge_s),
      peerWindows_(opts_.windowCapacity, opts_.windowMaxAge_s),
      tracking_(opts_.tracking.value_or(est_ && est_->name() == "default")),
      tracker_(opts_.tracker),
      scan_(std::make_unique<CandidateScan>())
{
}

BearingProcessor::~BearingProcessor() = default;
BearingProcessor::BearingProcessor(BearingProcessor&&) noexcept = default;
BearingProcessor& BearingProcessor::operator=(BearingProcessor&&) noexcept = default;

void BearingProcessor::findCandidates(const BearingResult& res)
{
    constexpr unsigned kBins = 180, kGroups = 4;
    constexpr size_t kMaxPeaks = 6;
    candidates_.clear();
    const CleanCsi& f = *frames_.back();
    CandidateScan& s = *scan_;
    if (s.layout != f.layout.get() || s.nRx != f.nRx)
    {
        s.layout = f.layout.get();
        s.nRx = f.nRx;
        s.rx = pre_.rxArray().firstElements(f.nRx);
        s.grid = detail::AngleGrid::make(s.rx, f.nRx, kBins);
        detail::groupFrequencies(*f.layout, kGroups, s.gf, s.gc);
        s.qf.prepare(s.rx, f.nRx, s.grid, s.gf);
    }
    if (res.hasDelay)
        detail::delayFilteredCovariances(frames_, res.delay_s, kGroups, s.R);
    else
        detail::sumCovariances(frames_, kGroups, false, s.R);
    s.qf.evaluate(s.R, s.spec);
    const double pMax = s.spec.maxCoeff();
    if (!(pMax > 0))
    {
        candidates_.push_back({res.aoa_rad, 1.0});
        return;
    }
    const double p0 = detail::groupedForm(s.rx, f.nRx, res.aoa_rad, s.gf, s.R);
    candidates_.push_back({res.aoa_rad, std::clamp(p0 / pMax, 0.0, 1.0)});
    const bool linear = s.rx.size() >= 2 && s.rx.isLinear();
    for (size_t i : detail::findPeaks1D(s.spec, s.grid.circular, kMaxPeaks))
    {
        const double theta = s.grid.at(detail::refinePeak1D(s.spec, i, s.grid.circular));
        double d = angleDistance(theta, res.aoa_rad);
        if (linear) d = std::min(d, angleDistance(s.rx.mirrorOf(theta), res.aoa_rad));
        if (d < 10 * M_PI / 180) continue;  // the estimator's own peak
        candidates_.push_back({theta, s.spec[Eigen::Index(i)] / pMax});
    }
}

void BearingProcessor::track(const CObservationWiFiCSI& csi)
{
    BearingResult& r = lastResult_;
    findCandidates(r);
    const auto pose = odometry_.empty() ? std::nullopt : odometryAt(csi.timestamp);
    const AntennaArray& rx = scan_->rx;
    lastDecision_ = tracker_.update(
        csi.transmitter, mrpt::Clock::toDouble(csi.timestamp), pose, rx, candidates_, r.aoaStd_rad);
    const BearingTracker::Decision& d = lastDecision_;
    if (d.chosen != 0)
    {
        // The track's candidate, stored as the estimators store a bearing (front half-plane
        // first, then its mirror).
        const bool linear = rx.size() >= 2 && rx.isLinear();
        double theta = wrapAngle(candidates_[d.chosen].theta_rad);
        if (linear && angleDistance(theta, rx.broadside()) > M_PI / 2) theta = rx.mirrorOf(theta);
        // Only a window that can't tell is swapped: the estimator's own choice becomes the
        // alternative, as likely as the track's was to it.
        // The estimator's other alternatives follow it, but the one the track took.
        auto alternatives = r.aoaAlternatives();
        AoaAlternative own;
        own.aoa_rad = r.aoa_rad;
        own.weight = std::clamp(
            alternatives.empty() ? candidates_[d.chosen].relativePower
                                 : alternatives.front().weight,
            0.0, 1.0);
        alternatives.erase(
            std::remove_if(
                alternatives.begin(), alternatives.end(),
                [&](const AoaAlternative& a)
                {
                    return std::min(
                               angleDistance(a.aoa_rad, theta),
                               linear ? angleDistance(rx.mirrorOf(a.aoa_rad), theta) : M_PI) <
                           10 * M_PI / 180;
                }),
            alternatives.end());
        alternatives.insert(alternatives.begin(), own);
        if (alternatives.size() > kMaxAoaAlternatives) alternatives.resize(kMaxAoaAlternatives);
        r.setAoaAlternatives(alternatives);
        r.aoa_rad = theta;
        r.aoaMirror_rad = linear ? rx.mirrorOf(theta) : theta;
    }
    // A bearing the confident track contradicts: σ reaches the track.
    if (d.confident && d.miss)
    {
        const double reach = 0.5 * d.disagreement_rad;
        r.aoaStd_rad = std::min(std::max(r.aoaStd_rad, reach), M_PI / 2);
        r.aoaDirectionStd_rad = std::min(std::max(r.aoaDirectionStd_rad, reach), M_PI / 2);
    }
}

void BearingProcessor::setTransmitterArray(const MacAddress& mac, AntennaArray array)
{
    txArrays_[mac] = std::move(array);
}

void BearingProcessor::setDefaultTransmitterArray(AntennaArray array)
{
    defaultTxArray_ = std::move(array);
}

const AntennaArray* BearingProcessor::txArrayOf(const MacAddress& mac) const
{
    const auto it = txArrays_.find(mac);
    if (it != txArrays_.end()) return &it->second;
    return defaultTxArray_ ? &*defaultTxArray_ : nullptr;
}

void BearingProcessor::addOdometry(mrpt::Clock::time_point t, const mrpt::math::TPose2D& odometry)
{
    const double ts = mrpt::Clock::toDouble(t);
    if (!odometry_.empty() && ts < odometry_.back().first)
        odometry_.clear();  // time went backwards (a new recording): start over
    odometry_.emplace_back(ts, odometry);
    while (odometry_.size() > 2 && odometry_.front().first < ts - opts_.odometryHistory_s)
        odometry_.pop_front();
}

std::optional<mrpt::math::TPose2D> BearingProcessor::odometryAt(mrpt::Clock::time_point t) const
{
    constexpr double kSlack_s = 0.25;
    if (odometry_.empty()) return std::nullopt;
    const double ts = mrpt::Clock::toDouble(t);
    if (ts < odometry_.front().first - kSlack_s || ts > odometry_.back().first + kSlack_s)
        return std::nullopt;
    const auto it = std::lower_bound(
        odometry_.begin(), odometry_.end(), ts,
        [](const std::pair<double, mrpt::math::TPose2D>& a, double v) { return a.first < v; });
    if (it == odometry_.begin()) return it->second;
    if (it == odometry_.end()) return odometry_.back().second;
    const auto& [ta, a] = *(it - 1);
    const auto& [tb, b] = *it;
    const double f = tb > ta ? (ts - ta) / (tb - ta) : 0.0;
    return mrpt::math::TPose2D(
        a.x + f * (b.x - a.x), a.y + f * (b.y - a.y),
        mrpt::math::wrapToPi(a.phi + f * mrpt::math::wrapToPi(b.phi - a.phi)));
}

void BearingProcessor::limitWindowByMotion()
{
    if (odometry_.empty() || frames_.size() < 2) return;
    const auto ref = odometryAt(frames_.back()->timestamp);
    if (!ref) return;
    size_t keepFrom = frames_.size() - 1;
    while (keepFrom > 0)
    {
        const auto p = odometryAt(frames_[keepFrom - 1]->timestamp);
        if (!p) break;
        const double moved = std::hypot(p->x - ref->x, p->y - ref->y);
        const double turned = std::abs(mrpt::math::wrapToPi(p->phi - ref->phi));
        if (moved > opts_.maxWindowTranslation_m || turned > opts_.maxWindowRotation_rad) break;
        --keepFrom;
    }
    frames_.erase(frames_.begin(), frames_.begin() + long(keepFrom));
}

CObservationWiFiBearing::Ptr BearingProcessor::process(
    const CObservationWiFiCSI& csi, RejectReason* reason)
{
    lastFrame_ = nullptr;
    lastResult_ = BearingResult();
    // A peer's recording of this robot is only kept, by the peer's MAC.
    const auto peer = opts_.peerRecordings.find(csi.sensorLabel);
    const bool peerRecording = peer != opts_.peerRecordings.end();
    CsiWindow& window =
        peerRecording ? peerWindows_.of(peer->second) : windows_.of(csi.transmitter);
    const RejectReason r = pre_.process(csi, window.slot());
    if (reason) *reason = r;
    if (r != RejectReason::Accepted) return nullptr;
    window.commit();
    if (peerRecording) return nullptr;
    lastFrame_ = &window.newest();

    EstimatorContext ctx;
    ctx.rxArray = &pre_.rxArray();
    ctx.txArrayOf = [this](const MacAddress& m) { return txArrayOf(m); };
    if (est_->syntheticAperture())
    {
        // Each estimate spans seconds of motion: one per interval, from the whole window.
        const double now = mrpt::Clock::toDouble(csi.timestamp);
        const auto last = lastAperture_.find(csi.transmitter);
        if (last != lastAperture_.end() && now - last->second < opts_.apertureInterval_s &&
            now >= last->second)
            return nullptr;
        lastAperture_[csi.transmitter] = now;
        window.recent(est_->framesWanted(), frames_);
        ctx.peerRecordingOf = [this](const MacAddress& peerMac)
        {
            std::vector<const CleanCsi*> out;
            peerWindows_.of(peerMac).recent(est_->framesWanted(), out);
            return out;
        };
        const mrpt::poses::CPose2D antenna(csi.sensorPose);
        ctx.antennaPoseAt =
            [this, antenna](mrpt::Clock::time_point t) -> std::optional<mrpt::math::TPose2D>
        {
            const auto robot = odometryAt(t);
            if (!robot) return std::nullopt;
            return (mrpt::poses::CPose2D(*robot) + antenna).asTPose();
        };
    }
    else
    {
        unsigned& since = sinceLast_[csi.transmitter];
        if (++since < opts_.stride) return nullptr;
        since = 0;
        // Without odometry only the last maxWindowSpanWithoutOdometry_s: the robot may turn.
        std::optional<double> span;
        if (odometry_.empty() && opts_.maxWindowSpanWithoutOdometry_s > 0)
            span = opts_.maxWindowSpanWithoutOdometry_s;
        window.recent(est_->framesWanted(), frames_, span);
        limitWindowByMotion();
    }
    if (!est_->estimate(frames_, ctx, lastResult_) || !lastResult_.valid) return nullptr;
    // A frame in a learnt jump state not confirmed yet: σ covers what its phase may be off by.
    double stateDoubt = 0;
    for (const CleanCsi* f : frames_) stateDoubt = std::max(stateDoubt, f->stateDoubt_rad);
    if (stateDoubt > 0)
    {
        BearingResult& doubtful = lastResult_;
        doubtful.aoaStd_rad = std::min(std::hypot(doubtful.aoaStd_rad, stateDoubt), M_PI / 2);
        doubtful.aoaDirectionStd_rad =
            std::min(std::hypot(doubtful.aoaDirectionStd_rad, stateDoubt), M_PI / 2);
    }
    lastDecision_ = BearingTracker::Decision();
    if (tracking_) track(csi);

    auto b = CObservationWiFiBearing::Create();
    const BearingResult& res = lastResult_;
    b->timestamp = csi.timestamp;
    b->sensorLabel = csi.sensorLabel + "_AOA";
    b->sensorPose = csi.sensorPose;
    b->transmitter = csi.transmitter;
    b->chanspec = csi.chanspec;
    b->rssi_dBm = csi.rssi_dBm;
    b->algorithm = est_->name();
    b->framesUsed = uint16_t(std::min<unsigned>(res.framesUsed, 65535));
    b->pathsDetected = uint8_t(std::min<unsigned>(res.pathsDetected, 255));
    b->aoa_rad = res.aoa_rad;
    b->aoaStd_rad = res.aoaStd_rad;
    b->aoaAmbiguous = res.aoaAmbiguous;
    b->aoaMirror_rad = res.aoaMirror_rad;
    b->hasAoaAlternative = res.hasAoaAlternative;
    b->aoaAlternative_rad = res.hasAoaAlternative ? res.aoaAlternative_rad : 0.0;
    b->aoaAlternativeWeight = res.hasAoaAlternative ? res.aoaAlternativeWeight : 0.0;
    b->aoaDirectionStd_rad = res.hasAoaAlternative ? res.aoaDirectionStd_rad : res.aoaStd_rad;
    b->moreAoaAlternatives.clear();
    if (res.hasAoaAlternative)
        for (const auto& a : res.moreAoaAlternatives)
            b->moreAoaAlternatives.push_back({a.aoa_rad, a.weight});
    const PhaseCalibration* txCal = lastFrame_->txCalibration;
    b->hasAod = res.hasAod && (txCal || opts_.uncalibratedAod);
    b->aod_rad = res.aod_rad;
    // The calibration's own error (what it left on its drive) adds to the estimator's.
    b->aodStd_rad = txCal ? std::hypot(res.aodStd_rad, txCal->aodResidual_rad) : res.aodStd_rad;
    b->aodAmbiguous = res.aodAmbiguous;
    b->aodMirror_rad = res.aodMirror_rad;
    b->hasDelay = res.hasDelay;
    b->delay_s = res.delay_s;
    b->quality = res.quality;
    return b;
}

}  // namespace mrpt_wifi::bearing
