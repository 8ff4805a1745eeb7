/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/obs/bearing/SyntheticAperture.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <unordered_set>

namespace mrpt_wifi::sar
{
namespace
{
/** The values of one chain pair at the reported subcarriers, in subcarrier order. */
bool chainValues(
    const CObservationWiFiCSI& f, unsigned rx, std::vector<int>& ks,
    std::vector<std::complex<double>>& h)
{
    if (rx >= f.nRx || f.nTx < 1 || !f.isPresent(0, rx)) return false;
    ks = f.dataSubcarriers();
    std::sort(ks.begin(), ks.end());
    h.resize(ks.size());
    for (size_t i = 0; i < ks.size(); ++i)
        h[i] = std::complex<double>(f.at(0, rx, subcarrierToBin(ks[i], f.nfft())));
    return true;
}
}  // namespace

namespace
{
/** Forward × reverse at the subcarriers `ks` (ascending), the product's delay slope removed,
 *  summed coherently (combinedProduct()). */
template <class ValueA, class ValueB>
std::optional<std::complex<double>> productOverSubcarriers(
    const std::vector<int>& ks, const ValueA& a, const ValueB& b, std::string* why)
{
    std::vector<std::complex<double>> p(ks.size());
    for (size_t i = 0; i < ks.size(); ++i) p[i] = a(i) * b(i);
    // Delay slope: least-squares line through the unwrapped phase across subcarriers (the
    // product's phase turns by well under π between neighbours at these delays). The
    // preprocessing's slope from neighbouring subcarriers' rotations
    // (CsiPreprocessor::estimatePhaseSlope) was tried on these products: on the WSR development
    // sets it took LOS_Set_A's bearing error from 2.7° to 29° mean (its profiles lose their peak).
    // (MRPT's unwrap2PiSequence adds at most one turn per value, not the running sum.)
    std::vector<double> phase(p.size());
    for (size_t i = 0; i < p.size(); ++i)
        phase[i] = i == 0 ? std::arg(p[i])
                          : phase[i - 1] + std::remainder(std::arg(p[i]) - phase[i - 1], 2 * M_PI);
    double mk = 0, mp = 0;
    for (size_t i = 0; i < p.size(); ++i) mk += ks[i], mp += phase[i];
    mk /= double(p.size()), mp /= double(p.size());
    double skp = 0, skk = 0;
    for (size_t i = 0; i < p.size(); ++i)
        skp += (ks[i] - mk) * (phase[i] - mp), skk += (ks[i] - mk) * (ks[i] - mk);
    const double slope = skk > 0 ? skp / skk : 0.0;
    std::complex<double> sum = 0;
    for (size_t i = 0; i < p.size(); ++i) sum += p[i] * std::polar(1.0, -slope * ks[i]);
    if (std::abs(sum) == 0)
    {
        if (why) *why = "zero channel";
        return std::nullopt;
    }
    return sum / double(p.size());
}
}  // namespace

std::optional<std::complex<double>> combinedProduct(
    const CObservationWiFiCSI& heardByMover, const CObservationWiFiCSI& heardByPeer,
    unsigned moverRx, unsigned peerRx, std::string* why)
{
    std::vector<int> ka, kb;
    std::vector<std::complex<double>> a, b;
    const auto fail = [&](const char* text) -> std::optional<std::complex<double>>
    {
        if (why) *why = text;
        return std::nullopt;
    };
    if (!chainValues(heardByMover, moverRx, ka, a)) return fail("mover's chain not in the frame");
    if (!chainValues(heardByPeer, peerRx, kb, b)) return fail("peer's chain not in the frame");
    if (ka != kb || ka.size() < 2) return fail("the two frames report different subcarriers");
    return productOverSubcarriers(
        ka, [&](size_t i) { return a[i]; }, [&](size_t i) { return b[i]; }, why);
}

std::optional<std::complex<double>> combinedProduct(
    const CleanCsi& heardByMover, const CleanCsi& heardByPeer, unsigned moverRx, unsigned peerRx,
    std::string* why)
{
    const auto fail = [&](const char* text) -> std::optional<std::complex<double>>
    {
        if (why) *why = text;
        return std::nullopt;
    };
    if (moverRx >= heardByMover.nRx || heardByMover.nTx < 1)
        return fail("mover's chain not in the frame");
    if (peerRx >= heardByPeer.nRx || heardByPeer.nTx < 1)
        return fail("peer's chain not in the frame");
    if (!heardByMover.layout || !heardByPeer.layout ||
        heardByMover.layout->subcarriers != heardByPeer.layout->subcarriers ||
        heardByMover.layout->size() < 2)
        return fail("the two frames report different subcarriers");
    const auto a = heardByMover.H.row(Eigen::Index(moverRx));
    const auto b = heardByPeer.H.row(Eigen::Index(peerRx));
    return productOverSubcarriers(
        heardByMover.layout->subcarriers,
        [&](size_t i) { return std::complex<double>(a[Eigen::Index(i)]); },
        [&](size_t i) { return std::complex<double>(b[Eigen::Index(i)]); }, why);
}

std::vector<uint64_t> unwrapCounter16(const std::vector<uint16_t>& counters)
{
    std::vector<uint64_t> out(counters.size());
    uint64_t epoch = 0;
    for (size_t i = 0; i < counters.size(); ++i)
    {
        if (i > 0 && int(counters[i]) - int(counters[i - 1]) < -32768) epoch += 65536;
        out[i] = epoch + counters[i];
    }
    return out;
}

std::vector<std::pair<size_t, size_t>> pairByCounter(
    const std::vector<uint64_t>& moverCounters, const std::vector<uint64_t>& peerCounters)
{
    std::unordered_map<uint64_t, size_t> peerIndex;  // first frame of each counter
    for (size_t j = 0; j < peerCounters.size(); ++j) peerIndex.emplace(peerCounters[j], j);
    std::vector<std::pair<size_t, size_t>> pairs;
    std::unordered_set<uint64_t> paired;
    for (size_t i = 0; i < moverCounters.size(); ++i)
        if (const auto it = peerIndex.find(moverCounters[i]);
            it != peerIndex.end() && paired.insert(moverCounters[i]).second)
            pairs.emplace_back(i, it->second);
    return pairs;
}

std::vector<uint64_t> frameCounters(const std::vector<CObservationWiFiCSI::Ptr>& frames)
{
    std::vector<uint16_t> c;
    c.reserve(frames.size());
    for (const auto& f : frames) c.push_back(f->firmwareCounter);
    return unwrapCounter16(c);
}

std::vector<PairedProduct> pairedProducts(
    const std::vector<CObservationWiFiCSI::Ptr>& heardByMover,
    const std::vector<CObservationWiFiCSI::Ptr>& heardByPeer, unsigned moverRx, unsigned peerRx,
    size_t* pairs)
{
    const auto matched = pairByCounter(frameCounters(heardByMover), frameCounters(heardByPeer));
    if (pairs) *pairs = matched.size();
    std::vector<PairedProduct> out;
    out.reserve(matched.size());
    for (const auto& [i, j] : matched)
        if (const auto h = combinedProduct(*heardByMover[i], *heardByPeer[j], moverRx, peerRx))
            out.push_back({mrpt::Clock::toDouble(heardByMover[i]->timestamp), *h});
    return out;
}

double reciprocityScore(
    const std::vector<CObservationWiFiCSI::Ptr>& heardByMover,
    const std::vector<CObservationWiFiCSI::Ptr>& heardByPeer, unsigned moverRx, unsigned peerRx)
{
    double sum = 0;
    size_t n = 0;
    std::vector<int> ka, kb;
    std::vector<std::complex<double>> a, b;
    for (const auto& [i, j] :
         pairByCounter(frameCounters(heardByMover), frameCounters(heardByPeer)))
    {
        if (!chainValues(*heardByMover[i], moverRx, ka, a) ||
            !chainValues(*heardByPeer[j], peerRx, kb, b) || ka != kb)
            continue;
        // Pearson correlation of the amplitudes across subcarriers.
        const size_t m = a.size();
        double ma = 0, mb = 0;
        for (size_t s = 0; s < m; ++s) ma += std::abs(a[s]), mb += std::abs(b[s]);
        ma /= double(m), mb /= double(m);
        double sab = 0, saa = 0, sbb = 0;
        for (size_t s = 0; s < m; ++s)
        {
            const double da = std::abs(a[s]) - ma, db = std::abs(b[s]) - mb;
            sab += da * db, saa += da * da, sbb += db * db;
        }
        if (saa <= 0 || sbb <= 0) continue;
        sum += sab / std::sqrt(saa * sbb);
        ++n;
    }
    return n ? sum / double(n) : 0.0;
}

std::optional<SarEstimate> estimateBearing(
    const std::vector<Exchange>& exchanges, const SarOptions& options, std::string& whyNot)
{
    std::vector<const Exchange*> valid;
    for (const auto& e : exchanges)
        if (std::isfinite(e.product.real()) && std::isfinite(e.product.imag()) &&
            std::abs(e.product) > 0 && std::isfinite(e.position.x) && std::isfinite(e.position.y))
            valid.push_back(&e);
    if (valid.size() < 3)
    {
        whyNot = "fewer than 3 usable exchanges (" + std::to_string(valid.size()) + ")";
        return std::nullopt;
    }
    // Each exchange stands for the path travelled around it, so uneven packet rates and lost
    // packets do not weigh parts of the aperture more than others, and a robot standing still
    // contributes nothing (its products add the same value to every direction).
    const size_t n = valid.size();
    std::vector<double> weight(n, 0.0);
    for (size_t i = 0; i < n; ++i)
    {
        const auto& prev = valid[i > 0 ? i - 1 : 0]->position;
        const auto& next = valid[i + 1 < n ? i + 1 : n - 1]->position;
        weight[i] = 0.5 * (prev - next).norm();
    }
    struct Sample
    {
        double dx, dy, w;
        std::complex<double> h;
    };
    std::vector<Sample> used;
    SarEstimate est;
    for (size_t i = 0; i < n; ++i)
    {
        if (weight[i] < options.minMotionPerPacket_m) continue;
        if (used.empty()) est.start = valid[i]->position, est.startTime_s = valid[i]->time_s;
        const auto& p = valid[i]->position;
        const auto& h = valid[i]->product;
        used.push_back(
            {p.x - est.start.x, p.y - est.start.y, weight[i],
             options.phaseOnly ? h / std::abs(h) : h});
        est.apertureLength_m += weight[i];
    }
    est.packetsUsed = used.size();
    if (est.apertureLength_m < options.minApertureLength_m)
    {
        whyNot = "the robot moved " + std::to_string(est.apertureLength_m) +
                 " m while exchanging packets (at least " +
                 std::to_string(options.minApertureLength_m) + " m needed)";
        return std::nullopt;
    }
    const double twoK = 2.0 * 2.0 * M_PI * options.carrier_Hz / kSpeedOfLightMps;
    std::vector<double> scales;  // cos ε of each elevation
    for (const double e : options.elevations_deg) scales.push_back(std::cos(mrpt::DEG2RAD(e)));
    if (scales.empty()) scales.push_back(1.0);
    std::vector<double> projection(used.size());
    const auto farField = [&](double phi)
    {
        const double c = std::cos(phi), s = std::sin(phi);
        for (size_t i = 0; i < used.size(); ++i) projection[i] = used[i].dx * c + used[i].dy * s;
        double power = 0;
        for (const double scale : scales)
        {
            std::complex<double> acc = 0;
            for (size_t i = 0; i < used.size(); ++i)
                acc += used[i].w * used[i].h * std::polar(1.0, -twoK * scale * projection[i]);
            power += std::norm(acc);
        }
        return power / double(scales.size());
    };
    const size_t nAz = size_t(std::lround(360.0 / options.azimuthStep_deg));
    const double step = 2 * M_PI / double(nAz);
    est.profile.resize(nAz);
    for (size_t a = 0; a < nAz; ++a) est.profile[a] = farField(-M_PI + double(a) * step);
    const size_t peak =
        size_t(std::max_element(est.profile.begin(), est.profile.end()) - est.profile.begin());
    const double peakPower = est.profile[peak];
    if (!(peakPower > 0))
    {
        whyNot = "flat profile";
        return std::nullopt;
    }
    for (auto& v : est.profile) v /= peakPower;
    for (const double v : est.profile) est.profileMean += v / double(nAz);
    {
        // Strong peaks: local maxima above the fraction, a weaker one within the separation
        // of a stronger one being part of its lobe.
        std::vector<SarPeak> maxima;
        for (size_t a = 0; a < nAz; ++a)
        {
            const double v = est.profile[a];
            if (v >= options.strongPeakFraction && v >= est.profile[(a + nAz - 1) % nAz] &&
                v > est.profile[(a + 1) % nAz])
                maxima.push_back({-M_PI + double(a) * step, v});
        }
        std::sort(
            maxima.begin(), maxima.end(),
            [](const SarPeak& x, const SarPeak& y) { return x.power > y.power; });
        for (const auto& m : maxima)
        {
            bool separate = true;
            for (const auto& kept : est.peaks)
                separate =
                    separate && std::abs(mrpt::math::wrapToPi(m.azimuth_rad - kept.azimuth_rad)) >=
                                    mrpt::DEG2RAD(options.peakSeparation_deg);
            if (separate) est.peaks.push_back(m);
        }
    }

    // Main lobe: down to the first minimum on each side; its half-power half-width gives σ,
    // the highest peak outside it the quality.
    const auto at = [&](long i)
    { return est.profile[size_t((i % long(nAz) + long(nAz)) % long(nAz))]; };
    long left = long(peak), right = long(peak);
    while (right - long(peak) < long(nAz) / 2 && at(right + 1) <= at(right)) ++right;
    while (long(peak) - left < long(nAz) / 2 && at(left - 1) <= at(left)) --left;
    double halfWidth = 0;
    for (const int dir : {-1, 1})
    {
        long i = long(peak);
        while (std::abs(i - long(peak)) < long(nAz) / 2 && at(i) > 0.5) i += dir;
        const double over = at(i - dir), under = at(i);
        const double frac = over > under ? (over - 0.5) / (over - under) : 0.0;
        halfWidth += 0.5 * (double(std::abs(i - long(peak)) - 1) + frac) * step;
    }
    double side = 0;
    for (long i = right + 1; i < left + long(nAz); ++i)
        if (at(i) >= at(i - 1) && at(i) >= at(i + 1)) side = std::max(side, at(i));
    est.quality = 1.0 - side;

    // Near-field refinement: the peer at range r along φ from the start; the phase of each
    // exchange is 2k·(|q − p| − r).
    // The far-field power at the peak (the near-field sums below are in the plane alone).
    double best = 0, bestPhi = -M_PI + double(peak) * step, bestRange = 0;
    {
        const double c = std::cos(bestPhi), s = std::sin(bestPhi);
        std::complex<double> acc = 0;
        for (const auto& u : used)
            acc += u.w * u.h * std::polar(1.0, -twoK * (u.dx * c + u.dy * s));
        best = std::norm(acc);
    }
    const double farPhi = bestPhi;
    const long halfSteps = long(std::lround(options.refineHalfWidth_deg / options.azimuthStep_deg));
    for (const double r : options.ranges_m)
        for (long a = options.refineWithinLobe ? std::max(-halfSteps, left - long(peak))
                                               : -halfSteps;
             a <= (options.refineWithinLobe ? std::min(halfSteps, right - long(peak)) : halfSteps);
             ++a)
        {
            const double phi = farPhi + double(a) * step;
            const double qx = r * std::cos(phi), qy = r * std::sin(phi);
            std::complex<double> acc = 0;
            for (const auto& u : used)
                acc += u.w * u.h * std::polar(1.0, twoK * (std::hypot(qx - u.dx, qy - u.dy) - r));
            const double power = std::norm(acc);
            if (power > best) best = power, bestPhi = phi, bestRange = r;
        }
    est.azimuth_rad = mrpt::math::wrapToPi(bestPhi);
    est.range_m = bestRange;

    // The path's main direction (principal axis of the weighted positions) and the estimate
    // mirrored across it: a straight path supports both equally.
    {
        double sw = 0, mx = 0, my = 0;
        for (const auto& u : used) sw += u.w, mx += u.w * u.dx, my += u.w * u.dy;
        mx /= sw, my /= sw;
        double cxx = 0, cyy = 0, cxy = 0;
        for (const auto& u : used)
            cxx += u.w * (u.dx - mx) * (u.dx - mx), cyy += u.w * (u.dy - my) * (u.dy - my),
                cxy += u.w * (u.dx - mx) * (u.dy - my);
        const double axis = 0.5 * std::atan2(2 * cxy, cxx - cyy);
        // Far field: the direction reflected across the axis. Near field: the fitted peer
        // reflected across the axis line through the path's mean position.
        est.mirror_rad = mrpt::math::wrapToPi(2 * axis - bestPhi);
        if (bestRange > 0)
        {
            const mrpt::math::TPoint2D v(
                bestRange * std::cos(bestPhi) - mx, bestRange * std::sin(bestPhi) - my);
            const double along = v.x * std::cos(axis) + v.y * std::sin(axis);
            const mrpt::math::TPoint2D mirrored(
                mx + 2 * along * std::cos(axis) - v.x, my + 2 * along * std::sin(axis) - v.y);
            est.mirror_rad = std::atan2(mirrored.y, mirrored.x);
            est.mirrorRange_m = mirrored.norm();
        }
        const double farMirror = mrpt::math::wrapToPi(2 * axis - farPhi);
        est.mirrorPower = est.profile[size_t(std::lround((farMirror + M_PI) / step) % long(nAz))];
    }
    double sumAbs = 0;
    for (const auto& u : used) sumAbs += u.w * std::abs(u.h);
    est.coherence = sumAbs > 0 ? std::sqrt(best) / sumAbs : 0.0;
    const double floor = mrpt::DEG2RAD(options.stdFloor_deg);
    est.azimuthStd_rad = std::sqrt(floor * floor + 0.25 * halfWidth * halfWidth);
    // Position errors along the path (a tracking camera's drift, a wrong latency) and
    // multipath leave products the fitted peer does not explain; the main lobe's width does
    // not show it, the coherence does.
    if (est.coherence > 0 && est.coherence < options.coherenceReference)
        est.azimuthStd_rad *=
            std::pow(options.coherenceReference / est.coherence, options.coherenceExponent);
    // A smooth position error bends the aperture: its effect on the bearing grows with the
    // error and shrinks with the path's length.
    const double fromPath = options.positionStdGain * options.positionStd_m / est.apertureLength_m;
    est.azimuthStd_rad = std::hypot(est.azimuthStd_rad, fromPath);
    est.lobeStd_rad = est.azimuthStd_rad;
    // The near-field fit may have moved the bearing onto another strong peak's lobe: that peak
    // is then the bearing, not an alternative to it.
    if (!est.peaks.empty())
    {
        est.peaks.front().azimuth_rad = est.azimuth_rad;
        est.peaks.erase(
            std::remove_if(
                est.peaks.begin() + 1, est.peaks.end(),
                [&](const SarPeak& p)
                {
                    return std::abs(mrpt::math::wrapToPi(p.azimuth_rad - est.azimuth_rad)) <
                           mrpt::DEG2RAD(options.peakSeparation_deg);
                }),
            est.peaks.end());
    }
    // Behind an obstacle a sharp peak can be a path around it: a floor measured on the WSR
    // development sets, higher with more strong peaks and with less coherence.
    const double coherenceFactor = est.coherence > 0 && est.coherence < options.stdCoherence
                                       ? std::pow(options.stdCoherence / est.coherence, 2)
                                       : 1.0;
    const double ambiguityFloor =
        mrpt::DEG2RAD(est.peaks.size() > 1 ? options.severalPeaksStd_deg : options.onePeakStd_deg) *
        coherenceFactor;
    est.azimuthStd_rad = std::max(est.azimuthStd_rad, ambiguityFloor);
    for (size_t i = 1; i < est.peaks.size() && i < 3; ++i)
    {
        const bool strong = est.peaks[i].power >= 0.6;
        est.peaks[i].weight = i == 1 ? (strong ? 0.29 : 0.07) : (strong ? 0.18 : 0.05);
    }
    return est;
}

std::string SyntheticApertureEstimator::description() const
{
    return "one antenna on a moving robot: forward x reverse channel of each exchange with a "
           "peer over the robot's path (WSR's synthetic aperture; needs the peer's recording "
           "and odometry)";
}

std::vector<std::string> SyntheticApertureEstimator::parameterKeys() const
{
    return {"aperture_s",  "min_aperture_m", "position_std_m",
            "mover_chain", "peer_chain",     "keep_profile"};
}

bool SyntheticApertureEstimator::estimate(
    const std::vector<const CleanCsi*>& frames, const bearing::EstimatorContext& ctx,
    bearing::BearingResult& result)
{
    result = bearing::BearingResult();
    last_.reset();
    hasProfile_ = false;
    const auto fail = [&](std::string why)
    {
        whyNot_ = std::move(why);
        return false;
    };
    if (frames.empty()) return fail("no frames");
    if (!ctx.peerRecordingOf || !ctx.antennaPoseAt)
        return fail("needs the peer's recording and the robot's poses");
    const CleanCsi& newest = *frames.back();
    const auto reverse = ctx.peerRecordingOf(newest.transmitter);
    if (reverse.empty())
        return fail(
            "no recording by " + newest.transmitter.asString() + " of this robot's packets");
    const auto newestPose = ctx.antennaPoseAt(newest.timestamp);
    if (!newestPose) return fail("no pose at the newest frame");

    // A robot that hops channels hears the peer on several carriers; an aperture is coherent
    // on one, so it is formed from the frames on the newest frame's channel.
    std::vector<const CleanCsi*> onChannel;
    for (const auto* f : frames)
        if (f->layout->centerFrequency_Hz == newest.layout->centerFrequency_Hz)
            onChannel.push_back(f);
    std::vector<uint16_t> ca, cb;
    for (const auto* f : onChannel) ca.push_back(f->frameCounter);
    for (const auto* f : reverse) cb.push_back(f->frameCounter);
    exchanges_.clear();
    for (const auto& [i, j] : pairByCounter(unwrapCounter16(ca), unwrapCounter16(cb)))
    {
        const auto product =
            combinedProduct(*onChannel[i], *reverse[j], opts_.moverChain, opts_.peerChain);
        const auto pose = ctx.antennaPoseAt(onChannel[i]->timestamp);
        if (product && pose)
            exchanges_.push_back(
                {mrpt::Clock::toDouble(onChannel[i]->timestamp), {pose->x, pose->y}, *product});
    }
    SarOptions options;
    options.carrier_Hz = newest.layout->centerFrequency_Hz;
    options.minApertureLength_m = opts_.minAperture_m;
    options.positionStd_m = opts_.positionStd_m;
    std::string whyNot;
    last_ = estimateBearing(exchanges_, options, whyNot);
    if (!last_) return fail(whyNot);
    const SarEstimate& est = *last_;

    // From the aperture's start to the newest pose, in the antenna's frame: through the fitted
    // peer position when the near field fitted best (a far-field direction is the same from
    // anywhere).
    const auto fromNewestPose = [&](double azimuthFromStart, double range)
    {
        double azimuth = azimuthFromStart;
        if (range > 0)
            azimuth = std::atan2(
                est.start.y + range * std::sin(azimuthFromStart) - newestPose->y,
                est.start.x + range * std::cos(azimuthFromStart) - newestPose->x);
        return mrpt::math::wrapToPi(azimuth - newestPose->phi);
    };
    result.valid = true;
    result.aoa_rad = fromNewestPose(est.azimuth_rad, est.range_m);
    result.aoaMirror_rad = result.aoa_rad;
    // A path too straight to tell the peer from its mirror image: both, as the linear arrays'
    // bearings carry them (the localization's likelihood takes the better of the two).
    if (est.mirrorPower >= kMirrorAmbiguity)
    {
        result.aoaAmbiguous = true;
        result.aoaMirror_rad = fromNewestPose(est.mirror_rad, est.mirrorRange_m);
    }
    result.aoaStd_rad = est.azimuthStd_rad;
    // The profile's other strong peaks (far field: the same direction from any pose).
    std::vector<bearing::AoaAlternative> alternatives;
    for (const auto& peak : est.peaks)
        if (peak.weight > 0 && alternatives.size() < bearing::kMaxAoaAlternatives)
            alternatives.push_back(
                {fromNewestPose(peak.azimuth_rad, 0), peak.weight, peak.power,
                 std::numeric_limits<double>::quiet_NaN()});
    std::sort(
        alternatives.begin(), alternatives.end(),
        [](const auto& x, const auto& y) { return x.weight > y.weight; });
    result.setAoaAlternatives(alternatives);
    result.aoaDirectionStd_rad = alternatives.empty() ? est.azimuthStd_rad : est.lobeStd_rad;
    result.quality = est.quality;
    result.framesUsed = unsigned(est.packetsUsed);
    result.pathsDetected = 1;
    if (opts_.keepProfile)
    {
        // In the antenna's frame at the newest pose, ascending.
        const size_t n = est.profile.size();
        std::vector<std::pair<double, float>> byAngle(n);
        for (size_t a = 0; a < n; ++a)
            byAngle[a] = {
                mrpt::math::wrapToPi(-M_PI + 2 * M_PI * double(a) / double(n) - newestPose->phi),
                float(est.profile[a])};
        std::sort(byAngle.begin(), byAngle.end());
        profile_.angles_rad.resize(n);
        profile_.delays_s = {0.0};
        profile_.values.resize(Eigen::Index(n), 1);
        for (size_t a = 0; a < n; ++a)
            profile_.angles_rad[a] = byAngle[a].first,
            profile_.values(Eigen::Index(a), 0) = byAngle[a].second;
        profile_.label = "synthetic-aperture Bartlett power (far field)";
        profile_.peakAngle_rad = result.aoa_rad;
        profile_.peakDelay_s = 0;
        profile_.hasPeak = true;
        hasProfile_ = true;
    }
    whyNot_.clear();
    return true;
}

}  // namespace mrpt_wifi::sar
