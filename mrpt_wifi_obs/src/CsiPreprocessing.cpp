/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/system/datetime.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

namespace mrpt_wifi
{
const char* toString(RejectReason r)
{
    switch (r)
    {
        case RejectReason::Accepted:
            return "accepted";
        case RejectReason::LowRssi:
            return "RSSI below the gate";
        case RejectReason::NoCompleteStream:
            return "no complete stream";
        case RejectReason::ArrayMismatch:
            return "more receive chains than array elements";
        case RejectReason::DeadAntenna:
            return "dead antenna";
        case RejectReason::NoCalibration:
            return "no calibration for the channel";
        case RejectReason::UnsupportedChannel:
            return "unsupported bandwidth";
        case RejectReason::SingleAntenna:
            return "one receive antenna: no angle of arrival (CSI still recorded)";
        case RejectReason::UnknownChainState:
            return "a receive chain in a jump state the calibration lacks (or unmeasurable)";
        case RejectReason::MissingCore:
            return "a receive core the array reads is not in the frame";
    }
    return "?";
}

// ---------------------------------------------------------------------------------------------
namespace
{
std::atomic<uint64_t> nextCacheId{1};
}

uint64_t CleanCsi::newDerivedOwner()
{
    return nextCacheId++;
}

void CleanCsi::invalidateCaches() const
{
    covGroups_ = txCovGroups_ = 0;
    contentId_ = nextCacheId++;
}

std::pair<size_t, size_t> CleanCsi::groupRange(size_t nSub, unsigned groups, unsigned g)
{
    return {nSub * g / groups, nSub * (g + 1) / groups};
}

namespace
{
constexpr unsigned kMaxRx = CObservationWiFiCSI::kMaxChains;

/** Upper triangle of Σ_{j ∈ [b, e), m} v v^H, v = the N receive antennas of stream m at
 *  subcarrier j, in split real/imaginary form. N at compile time: the accumulators stay in
 *  registers (with a runtime N they go through memory on every update). */
template <unsigned N>
void accumulateCovariance(
    const std::complex<float>* H, Eigen::Index rows, unsigned nTx, Eigen::Index b, Eigen::Index e,
    float (&accRe)[kMaxRx][kMaxRx], float (&accIm)[kMaxRx][kMaxRx])
{
    float re[N][N] = {}, im[N][N] = {};
    for (Eigen::Index j = b; j < e; ++j)
    {
        const std::complex<float>* col = H + j * rows;
        for (unsigned m = 0; m < nTx; ++m)
        {
            const std::complex<float>* v = col + m * N;
            for (unsigned r = 0; r < N; ++r)
            {
                const float ar = v[r].real(), ai = v[r].imag();
                for (unsigned c = r; c < N; ++c)
                {
                    // v_r · conj(v_c)
                    re[r][c] += ar * v[c].real() + ai * v[c].imag();
                    im[r][c] += ai * v[c].real() - ar * v[c].imag();
                }
            }
        }
    }
    for (unsigned r = 0; r < N; ++r)
        for (unsigned c = r; c < N; ++c) accRe[r][c] = re[r][c], accIm[r][c] = im[r][c];
}

template <unsigned N = 1>
void accumulateCovariance(
    unsigned nRx, const std::complex<float>* H, Eigen::Index rows, unsigned nTx, Eigen::Index b,
    Eigen::Index e, float (&accRe)[kMaxRx][kMaxRx], float (&accIm)[kMaxRx][kMaxRx])
{
    if constexpr (N <= kMaxRx)
    {
        if (nRx == N) return accumulateCovariance<N>(H, rows, nTx, b, e, accRe, accIm);
        accumulateCovariance<N + 1>(nRx, H, rows, nTx, b, e, accRe, accIm);
    }
}
}  // namespace

const std::vector<Eigen::MatrixXcd>& CleanCsi::groupCovariances(unsigned groups) const
{
    if (covGroups_ == groups && cov_.size() == groups) return cov_;
    cov_.resize(groups);
    const Eigen::Index nSub = H.cols(), rows = H.rows();
    // One pass over the columns (contiguous: streams × antennas), accumulating the upper
    // triangle of Σ v v^H per stream block in split real/imaginary form (small Eigen products
    // per block cost more in call overhead than in arithmetic here).
    for (unsigned g = 0; g < groups; ++g)
    {
        const auto [b, e] = groupRange(size_t(nSub), groups, g);
        float accRe[kMaxRx][kMaxRx] = {}, accIm[kMaxRx][kMaxRx] = {};
        accumulateCovariance(
            nRx, H.data(), rows, nTx, Eigen::Index(b), Eigen::Index(e), accRe, accIm);
        auto& R = cov_[g];
        R.resize(nRx, nRx);
        for (unsigned r = 0; r < nRx; ++r)
            for (unsigned c = r; c < nRx; ++c)
            {
                R(r, c) = {accRe[r][c], accIm[r][c]};
                R(c, r) = std::conj(R(r, c));
            }
    }
    covGroups_ = groups;
    return cov_;
}

const std::vector<Eigen::MatrixXcd>& CleanCsi::txGroupCovariances(unsigned groups) const
{
    if (txCovGroups_ == groups && txCov_.size() == groups) return txCov_;
    txCov_.resize(groups);
    const Eigen::Index nSub = H.cols();
    for (unsigned g = 0; g < groups; ++g)
    {
        const auto [b, e] = groupRange(size_t(nSub), groups, g);
        Eigen::MatrixXcd acc = Eigen::MatrixXcd::Zero(nTx, nTx);
        for (unsigned i = 0; i < nRx; ++i)
        {
            // Rows i, nRx + i, 2·nRx + i, ...: one receive antenna across the streams.
            Eigen::MatrixXcf rows(nTx, Eigen::Index(e - b));
            for (unsigned m = 0; m < nTx; ++m)
                rows.row(m) =
                    H.block(Eigen::Index(m * nRx + i), Eigen::Index(b), 1, Eigen::Index(e - b));
            acc += (rows * rows.adjoint()).cast<std::complex<double>>();
        }
        txCov_[g] = acc;
    }
    txCovGroups_ = groups;
    return txCov_;
}

// ---------------------------------------------------------------------------------------------
CsiPreprocessor::CsiPreprocessor(
    PreprocessOptions options, AntennaArray rxArray, CalibrationStore calib)
    : options_(options), rxArray_(std::move(rxArray)), calib_(std::move(calib))
{
}

std::shared_ptr<const SubcarrierLayout> CsiPreprocessor::layoutFor(const Chanspec& cs)
{
    auto layout = std::make_shared<SubcarrierLayout>();
    layout->chanspec = cs;
    layout->centerFrequency_Hz = cs.centerFrequencyHz();
    const auto overwritten = firmwareOverwrittenSubcarriers(cs.bandwidthMHz);
    for (int k : dataSubcarriers(cs.bandwidthMHz))
    {
        if (options_.excludeFirmwareOverwritten &&
            std::find(overwritten.begin(), overwritten.end(), k) != overwritten.end())
            continue;
        layout->subcarriers.push_back(k);
        layout->bins.push_back(uint16_t(subcarrierToBin(k, cs.nfft())));
        layout->frequencies_Hz.push_back(subcarrierFrequencyHz(cs, k));
    }
    return layout;
}

std::shared_ptr<const SubcarrierLayout> CsiPreprocessor::layoutFor(const CObservationWiFiCSI& in)
{
    const Chanspec& cs = in.chanspec;
    const uint32_t channelKey = (uint32_t(cs.centerChannel) << 16) | uint32_t(cs.bandwidthMHz);
    // Consecutive frames almost always share the layout: no key copy, no map lookup then.
    if (lastLayout_ && lastLayoutKey_.first == channelKey &&
        lastLayoutKey_.second == in.subcarrierIndices)
        return lastLayout_;
    auto key = std::make_pair(channelKey, in.subcarrierIndices);
    auto it = layouts_.find(key);
    if (it != layouts_.end())
    {
        lastLayoutKey_ = it->first;
        return lastLayout_ = it->second;
    }
    if (in.subcarrierIndices.empty())
    {
        lastLayoutKey_ = key;
        return lastLayout_ = layouts_.emplace(std::move(key), layoutFor(cs)).first->second;
    }

    auto layout = std::make_shared<SubcarrierLayout>();
    layout->chanspec = cs;
    layout->centerFrequency_Hz = cs.centerFrequencyHz();
    layout->sourceListed = true;
    const int half = int(cs.nfft() / 2);
    for (size_t j = 0; j < in.subcarrierIndices.size(); ++j)
    {
        const int k = in.subcarrierIndices[j];
        if (k < -half || k >= half || (j > 0 && k <= in.subcarrierIndices[j - 1]))
            throw std::invalid_argument(
                "subcarrier list of a " + in.source + " frame on " + cs.asString() + ": index " +
                std::to_string(k) + " at position " + std::to_string(j) +
                (k < -half || k >= half ? " is outside ±" + std::to_string(half)
                                        : " is not above the previous one"));
        layout->subcarriers.push_back(k);
        layout->bins.push_back(uint16_t(subcarrierToBin(k, cs.nfft())));
        layout->frequencies_Hz.push_back(subcarrierFrequencyHz(cs, k));
    }
    lastLayoutKey_ = key;
    return lastLayout_ = layouts_.emplace(std::move(key), std::move(layout)).first->second;
}

CsiPreprocessor::ChannelCache& CsiPreprocessor::cacheFor(
    const std::shared_ptr<const SubcarrierLayout>& layout, unsigned nRx)
{
    const auto key = std::make_pair(layout.get(), nRx);
    auto it = caches_.find(key);
    if (it != caches_.end()) return it->second;

    const Chanspec& cs = layout->chanspec;
    ChannelCache c;
    c.layout = layout;
    const size_t nSub = c.layout->size();
    c.sign = Eigen::VectorXf::Ones(Eigen::Index(nSub));
    c.signImag = Eigen::VectorXf::Zero(Eigen::Index(nSub));
    // The sub-band sign quirks are the Nexmon firmware's: not for sources with their own list.
    const bool nexmonLayout = !layout->sourceListed;
    for (size_t j = 0; j < nSub && nexmonLayout; ++j)
    {
        const int k = c.layout->subcarriers[j];
        const bool flip80 = cs.bandwidthMHz == 80 && options_.correctSubbandSign80;
        const bool flip160 = cs.bandwidthMHz == 160 && options_.correctSubbandSign160;
        if ((flip80 || flip160) && inNegatedSubband(k, cs.bandwidthMHz))
        {
            c.sign[Eigen::Index(j)] = -1.f;
            c.hasSignCorrection = true;
        }
        if (cs.bandwidthMHz == 40 && options_.correctSubbandSign40 && k < 0)
        {
            c.sign[Eigen::Index(j)] = 0.f;
            c.signImag[Eigen::Index(j)] = -1.f;
            c.hasSignCorrection = true;
        }
    }
    c.calibration = calib_.find(rxArray_.name, cs, nRx);
    if (c.calibration)
    {
        c.calibrationFactors.resize(nRx, Eigen::Index(nSub));
        for (unsigned i = 0; i < nRx; ++i)
        {
            const double gain = std::pow(10.0, -c.calibration->gainAt(i) / 20.0);
            for (size_t j = 0; j < nSub; ++j)
                c.calibrationFactors(i, Eigen::Index(j)) = std::complex<float>(
                    std::polar(gain, -c.calibration->phaseAt(i, c.layout->subcarriers[j])));
        }
    }
    c.states = ChainStateTracker(nRx, c.calibration, options_.chainStates, cs.bandwidthMHz);
    return caches_.emplace(key, std::move(c)).first->second;
}

const CsiPreprocessor::TransmitterCache& CsiPreprocessor::transmitterCacheFor(
    const MacAddress& mac, const SubcarrierLayout& layout, unsigned streams)
{
    const Chanspec& cs = layout.chanspec;
    const auto key =
        std::make_pair(mac, (uint32_t(cs.centerChannel) << 16) | (uint32_t(cs.bandwidthMHz) << 4));
    auto it = txCaches_.find(key);
    if (it != txCaches_.end() && (!it->second.calibration || it->second.factors.rows() >= streams))
        return it->second;
    TransmitterCache c;
    c.calibration = calib_.findTransmitter(mac, cs, streams);
    if (c.calibration)
    {
        const auto chains = Eigen::Index(c.calibration->antennas());
        c.factors.resize(chains, Eigen::Index(layout.size()));
        for (Eigen::Index m = 0; m < chains; ++m)
        {
            const double gain = std::pow(10.0, -c.calibration->gainAt(size_t(m)) / 20.0);
            for (size_t j = 0; j < layout.size(); ++j)
                c.factors(m, Eigen::Index(j)) = std::complex<float>(
                    std::polar(gain, -c.calibration->phaseAt(size_t(m), layout.subcarriers[j])));
        }
    }
    return txCaches_[key] = std::move(c);
}

RejectReason CsiPreprocessor::elementRows(
    const CObservationWiFiCSI& in, std::vector<unsigned>& rows) const
{
    rows.clear();
    // Without `cores` in the array file, element i reads core i, and a frame uses as many
    // elements as it has rows (a receiver with fewer chains than the array).
    const size_t n = rxArray_.cores.empty() ? in.nRx : rxArray_.size();
    if (n > rxArray_.size()) return RejectReason::ArrayMismatch;
    for (size_t i = 0; i < n; ++i)
    {
        const int row = in.rowOfCore(rxArray_.coreOf(i));
        if (row < 0) return RejectReason::MissingCore;
        rows.push_back(unsigned(row));
    }
    return RejectReason::Accepted;
}

std::string CsiPreprocessor::coreMismatchMessage(const CObservationWiFiCSI& in) const
{
    std::vector<unsigned> rows;
    const RejectReason r = elementRows(in, rows);
    if (r == RejectReason::Accepted) return {};
    std::string arrayCores;
    for (size_t i = 0; i < (rxArray_.cores.empty() ? in.nRx : rxArray_.size()); ++i)
        arrayCores += (i ? ", " : "") + std::to_string(rxArray_.coreOf(i));
    const std::string array = "the array '" + rxArray_.name + "'" +
                              (rxArray_.sourcePath.empty() ? "" : " (" + rxArray_.sourcePath + ")");
    if (r == RejectReason::ArrayMismatch)
        return "the CSI has " + std::to_string(in.nRx) + " receive chains (cores " +
               in.rowCoresAsString() + ") but " + array + " has " +
               std::to_string(rxArray_.size()) +
               " elements; give an array with one element per core, or name the cores it "
               "reads with 'cores: [...]' in its file";
    return "the CSI holds receive cores " + in.rowCoresAsString() + " but " + array +
           " reads cores " + arrayCores +
           (rxArray_.cores.empty()
                ? " (element i = core i); a router with only some cores enabled (core mask) "
                  "needs an array file with one element per enabled core and 'cores: [" +
                      in.rowCoresAsString() + "]'"
                : "; check the array file's 'cores' against the router's core mask");
}

void CsiPreprocessor::checkCompatible(
    const Chanspec& cs, unsigned nRx, const std::vector<uint8_t>& rxCores)
{
    CObservationWiFiCSI shape;
    shape.nRx = uint8_t(nRx);
    shape.rxCores = rxCores;
    std::vector<unsigned> rows;
    if (elementRows(shape, rows) != RejectReason::Accepted)
        throw std::invalid_argument(coreMismatchMessage(shape));
    CObservationWiFiCSI standard;
    standard.chanspec = cs;
    // Throws for an unsupported bandwidth, then CalibrationError for a mismatching calibration.
    const auto& c = cacheFor(layoutFor(standard), unsigned(rows.size()));
    if (options_.requireCalibration && !c.calibration)
        throw CalibrationError(
            "no phase calibration for device '" + rxArray_.name + "' on " + cs.asString() +
            " in '" + calib_.path() + "'");
}

double CsiPreprocessor::estimatePhaseSlope(
    const Eigen::Ref<const Eigen::MatrixXcf>& H, const std::vector<int>& k)
{
    // Σ conj(h_j)·h_{j+1} per spacing k_{j+1} − k_j: its angle is spacing × slope (+ noise).
    constexpr int kMaxGap = 8;
    std::array<std::complex<double>, kMaxGap + 1> acc{};
    std::array<size_t, kMaxGap + 1> count{};
    for (size_t j = 0; j + 1 < k.size(); ++j)
    {
        const int gap = k[j + 1] - k[j];
        if (gap < 1 || gap > kMaxGap) continue;
        const auto c = H.col(Eigen::Index(j + 1)).dot(H.col(Eigen::Index(j)));  // Σ conj(a)·b
        acc[size_t(gap)] += std::conj(std::complex<double>(c));
        ++count[size_t(gap)];
    }
    const size_t dominant = size_t(std::max_element(count.begin(), count.end()) - count.begin());
    if (count[dominant] == 0) return 0;
    // Contiguous layouts (Nexmon): neighbours only, as the gaps at pilots add nothing.
    if (dominant == 1) return std::arg(acc[1]);
    const double coarse = std::arg(acc[dominant]) / double(dominant);
    double num = 0, den = 0;
    for (size_t g = 1; g <= size_t(kMaxGap); ++g)
    {
        if (!count[g]) continue;
        const double w = std::abs(acc[g]);
        const double residual = std::arg(acc[g] * std::polar(1.0, -coarse * double(g)));
        num += w * double(g) * residual;
        den += w * double(g * g);
    }
    return den > 0 ? coarse + num / den : coarse;
}

RejectReason CsiPreprocessor::process(const CObservationWiFiCSI& in, CleanCsi& out)
{
    if (in.rssi_dBm != 0 && in.rssi_dBm < options_.minRssi_dBm) return RejectReason::LowRssi;
    const RejectReason fits = elementRows(in, rows_);
    if (fits != RejectReason::Accepted) return fits;
    const auto& elementRow = rows_;
    const auto nRx = unsigned(elementRow.size());
    if (nRx < 2 && !options_.acceptSingleAntenna) return RejectReason::SingleAntenna;
    const unsigned nfft = in.nfft();
    const unsigned bw = in.chanspec.bandwidthMHz;
    if (bw != 20 && bw != 40 && bw != 80 && bw != 160) return RejectReason::UnsupportedChannel;
    if (in.csi.size() < size_t(in.nTx) * in.nRx * nfft) return RejectReason::NoCompleteStream;
    ChannelCache& cache = cacheFor(layoutFor(in), nRx);
    if (options_.requireCalibration && !cache.calibration) return RejectReason::NoCalibration;
    const SubcarrierLayout& layout = *cache.layout;
    const size_t nSub = layout.size();

    // Streams that arrived on every antenna, with energy on every antenna.
    out.streamIndex.clear();
    bool sawDead = false;
    for (unsigned m = 0; m < in.nTx && out.streamIndex.size() < options_.maxStreams; ++m)
    {
        bool complete = true, dead = false;
        for (unsigned i = 0; i < nRx && complete; ++i)
        {
            if (!in.isPresent(m, elementRow[i]))
            {
                complete = false;
                break;
            }
            const auto* p = in.pair(m, elementRow[i]);
            float energy = 0;
            for (uint16_t b : layout.bins) energy += std::norm(p[b]);
            if (!(energy > 0) || !std::isfinite(energy)) dead = true;
        }
        if (!complete) continue;
        if (dead)
        {
            sawDead = true;
            continue;
        }
        out.streamIndex.push_back(uint8_t(m));
    }
    if (out.streamIndex.empty())
        return sawDead ? RejectReason::DeadAntenna : RejectReason::NoCompleteStream;

    out.timestamp = in.timestamp;
    out.transmitter = in.transmitter;
    out.chanspec = in.chanspec;
    out.sensorPose = in.sensorPose;
    out.rssi_dBm = in.rssi_dBm;
    out.sequenceNumber = in.sequenceNumber;
    out.frameCounter = in.firmwareCounter;
    out.nRx = nRx;
    out.nTx = unsigned(out.streamIndex.size());
    out.layout = cache.layout;
    out.calibrated = cache.calibration != nullptr;
    out.invalidateCaches();
    out.H.resize(Eigen::Index(out.nTx * nRx), Eigen::Index(nSub));

    // Gather and sign-correct.
    for (unsigned s = 0; s < out.nTx; ++s)
        for (unsigned i = 0; i < nRx; ++i)
        {
            const auto* p = in.pair(out.streamIndex[s], elementRow[i]);
            auto row = out.H.row(Eigen::Index(s * nRx + i));
            for (size_t j = 0; j < nSub; ++j) row[Eigen::Index(j)] = p[layout.bins[j]];
            if (cache.hasSignCorrection)
                for (size_t j = 0; j < nSub; ++j)
                    row[Eigen::Index(j)] *= std::complex<float>(
                        cache.sign[Eigen::Index(j)], cache.signImag[Eigen::Index(j)]);
        }

    // Masked bins hold no measurement: zero now (no weight in the slopes), repaired below.
    std::vector<size_t> masked;
    for (uint16_t b : in.maskedBins)
    {
        const auto it = std::lower_bound(layout.bins.begin(), layout.bins.end(), b);
        if (it != layout.bins.end() && *it == b)
        {
            masked.push_back(size_t(it - layout.bins.begin()));
            out.H.col(Eigen::Index(masked.back())).setZero();
        }
    }

    // Jump states: classify each chain, then undo its state's delay and phase (relative to the
    // chain's reference state, in which the calibration holds).
    out.chainDelay_s.clear();
    out.chainState.clear();
    int learning = -1;  // a chain in a state the calibration lacks, whose phase is being learnt
    if (options_.trackChainStates)
    {
        measureChainDelays(out.H, nRx, layout.subcarriers, out.chainDelay_s, chainCoherence_);
        cache.states.classify(out.chainDelay_s, chainCoherence_, out.chainState);
        for (unsigned i = 1; i < nRx && cache.states.applies(); ++i)
        {
            if (out.chainState[i] == kUnknownChainState) return RejectReason::UnknownChainState;
            const ChainStateInfo& st = cache.states.info(i, out.chainState[i]);
            if (!st.resolved())
            {
                if (learning >= 0) return RejectReason::UnknownChainState;  // one at a time
                learning = int(i);
            }
            if (st.deltaDelay_s == 0 && st.deltaPhase_rad == 0) continue;
            const double w = 2 * M_PI * kSubcarrierSpacingHz * st.deltaDelay_s;
            for (unsigned s = 0; s < out.nTx; ++s)
            {
                auto row = out.H.row(Eigen::Index(s * nRx + i));
                for (size_t j = 0; j < nSub; ++j)
                    row[Eigen::Index(j)] *= std::complex<float>(
                        std::polar(1.0, w * layout.subcarriers[j] - st.deltaPhase_rad));
            }
        }
    }

    if (cache.calibration)
        for (unsigned s = 0; s < out.nTx; ++s)
            for (unsigned i = 0; i < nRx; ++i)
            {
                auto row = out.H.row(Eigen::Index(s * nRx + i));
                row = row.cwiseProduct(cache.calibrationFactors.row(i));
            }

    out.removedSlope_rad = 0;
    out.removedDelay_s = 0;
    if (options_.removeSamplingTimeOffset)
    {
        const auto& ks = layout.subcarriers;
        for (unsigned m = 0; m < out.nTx; ++m)
        {
            auto rows = out.H.middleRows(Eigen::Index(m * nRx), nRx);
            const double slope = estimatePhaseSlope(rows, ks);
            if (m == 0)
            {
                out.removedSlope_rad = slope;
                out.removedDelay_s = -slope / (2 * M_PI * kSubcarrierSpacingHz);
            }
            // e^{−j·slope·k} by recurrence along consecutive subcarriers (a sincos per gap only).
            const std::complex<double> step = std::polar(1.0, -slope);
            std::complex<double> z = std::polar(1.0, -slope * ks[0]);
            for (size_t j = 0; j < nSub; ++j)
            {
                if (j > 0) z = ks[j] - ks[j - 1] == 1 ? z * step : std::polar(1.0, -slope * ks[j]);
                rows.col(Eigen::Index(j)) *= std::complex<float>(z);
            }
        }
        // Common phase (CFO): the first row's mean phase becomes zero, for every stream alike.
        const std::complex<float> ref = out.H.row(0).sum();
        if (std::abs(ref) > 0) out.H *= std::conj(ref) / std::abs(ref);
    }

    // Transmit chains: after the per-stream slope removal, as wifi-calibrate measured them.
    out.txCalibration = nullptr;
    if (options_.applyTransmitterCalibration && out.nTx > 1 && !calib_.empty())
    {
        const unsigned highest = *std::max_element(out.streamIndex.begin(), out.streamIndex.end());
        const TransmitterCache& tc = transmitterCacheFor(in.transmitter, layout, highest + 1);
        if (tc.calibration)
        {
            for (unsigned s = 0; s < out.nTx; ++s)
            {
                const auto f = tc.factors.row(out.streamIndex[s]);
                for (unsigned i = 0; i < nRx; ++i)
                {
                    auto row = out.H.row(Eigen::Index(s * nRx + i));
                    row = row.cwiseProduct(f);
                }
            }
            out.txCalibration = tc.calibration;
        }
    }

    // Repair masked subcarriers from their nearest unmasked neighbours (linear, complex).
    if (!masked.empty())
    {
        std::vector<bool> isMasked(nSub, false);
        for (size_t j : masked) isMasked[j] = true;
        for (size_t j : masked)
        {
            long lo = long(j) - 1, hi = long(j) + 1;
            while (lo >= 0 && isMasked[size_t(lo)]) --lo;
            while (hi < long(nSub) && isMasked[size_t(hi)]) ++hi;
            const auto& k = layout.subcarriers;
            if (lo >= 0 && hi < long(nSub))
            {
                const float t = float(k[j] - k[size_t(lo)]) / float(k[size_t(hi)] - k[size_t(lo)]);
                out.H.col(Eigen::Index(j)) =
                    (1 - t) * out.H.col(Eigen::Index(lo)) + t * out.H.col(Eigen::Index(hi));
            }
            else if (lo >= 0)
                out.H.col(Eigen::Index(j)) = out.H.col(Eigen::Index(lo));
            else if (hi < long(nSub))
                out.H.col(Eigen::Index(j)) = out.H.col(Eigen::Index(hi));
        }
    }

    if (options_.normalizePower)
    {
        const float meanPower = out.H.squaredNorm() / float(out.H.size());
        if (meanPower > 0) out.H *= 1.0f / std::sqrt(meanPower);
    }
    if (learning >= 0)
    {
        learnChainState(cache, out, unsigned(learning));
        return RejectReason::UnknownChainState;
    }
    out.stateDoubt_rad = 0;
    if (options_.trackChainStates && options_.chainStates.verify && cache.states.applies())
        verifyChainStates(cache, out);
    return RejectReason::Accepted;
}

namespace
{
/** The bearing in the array's search interval where `power` peaks: a 1° grid, then `fineStep`
 *  within ±1° of its best. */
template <typename PowerFn>
double peakBearing(const AntennaArray& array, PowerFn power, double fineStep)
{
    const auto [lo, hi] = array.searchInterval();
    double best = lo, top = -1;
    for (double t = lo; t <= hi; t += M_PI / 180)
        if (const double p = power(t); p > top) top = p, best = t;
    const double coarse = best;
    for (double t = coarse - M_PI / 180; t <= coarse + M_PI / 180; t += fineStep)
        if (const double p = power(t); p > top) top = p, best = t;
    return best;
}

/** Wideband Bartlett power of the chains in `use` at bearing θ from sub-band covariances:
 *  Σ_g a_g^H R_g a_g, a = the chains' steering at the sub-band's centre frequency. The
 *  array is 7.8 cm wide, so across a 20 MHz sub-band its steering moves by < 0.03 rad. */
struct SubbandBartlett
{
    const AntennaArray* array = nullptr;
    const std::vector<Eigen::MatrixXcd>* R = nullptr;
    std::vector<double> centre_Hz;

    std::complex<double> steer(unsigned i, double theta, size_t g) const
    {
        return std::polar(1.0, array->steeringPhase(i, theta, centre_Hz[g]));
    }
    /** Σ_g Σ_{k,l ∈ use} conj(a_k) R_g(k,l) a_l, chain `turned` rotated by e^{jδ}. */
    double power(double theta, unsigned nRx, int excluded, int turned = -1, double delta = 0) const
    {
        double p = 0;
        std::complex<double> a[CObservationWiFiCSI::kMaxChains];
        for (size_t g = 0; g < R->size(); ++g)
        {
            for (unsigned k = 0; k < nRx; ++k)
                a[k] = int(k) == excluded ? 0.0
                                          : steer(k, theta, g) *
                                                (int(k) == turned ? std::polar(1.0, -delta) : 1.0);
            const auto& Rg = (*R)[g];
            for (unsigned k = 0; k < nRx; ++k)
                for (unsigned l = 0; l < nRx; ++l)
                    p += std::real(std::conj(a[k]) * Rg(k, l) * a[l]);
        }
        return p;
    }
    double best(unsigned nRx, int excluded, int turned = -1, double delta = 0) const
    {
        return peakBearing(
            *array, [&](double t) { return power(t, nRx, excluded, turned, delta); }, M_PI / 1800);
    }
    /** Chain i's residual phasor against the others' steered sum at θ, per sub-band summed;
     *  `coherence`: how well the sub-bands agree (|Σ| / Σ|·|). */
    std::complex<double> residual(unsigned i, double theta, unsigned nRx, double& coherence) const
    {
        std::complex<double> z{0, 0};
        double magnitude = 0;
        for (size_t g = 0; g < R->size(); ++g)
        {
            std::complex<double> zg{0, 0};
            for (unsigned k = 0; k < nRx; ++k)
                if (k != i)
                    zg += std::conj(steer(i, theta, g)) * steer(k, theta, g) * (*R)[g](i, k);
            z += zg;
            magnitude += std::abs(zg);
        }
        coherence = magnitude > 0 ? std::abs(z) / magnitude : 0.0;
        return z;
    }
};
}  // namespace

void CsiPreprocessor::verifyChainStates(ChannelCache& cache, CleanCsi& f)
{
    const unsigned nRx = f.nRx;
    bool anyLearnt = false;
    for (unsigned i = 1; i < nRx; ++i)
        anyLearnt = anyLearnt ||
                    cache.states.info(i, f.chainState[i]).origin == ChainStateOrigin::LearntOnline;
    if (!anyLearnt) return;
    constexpr unsigned kGroups = 4;
    SubbandBartlett b;
    b.array = &rxArray_;
    b.R = &f.groupCovariances(kGroups);
    for (unsigned g = 0; g < kGroups; ++g)
    {
        const auto [lo, hi] = CleanCsi::groupRange(f.layout->size(), kGroups, g);
        double sum = 0;
        for (size_t j = lo; j < hi; ++j) sum += f.layout->frequencies_Hz[j];
        b.centre_Hz.push_back(hi > lo ? sum / double(hi - lo) : f.layout->centerFrequency_Hz);
    }
    double theta0 = NAN;
    const ChainStateOptions& opts = cache.states.options();
    for (unsigned i = 1; i < nRx; ++i)
    {
        const ChainStateInfo& st = cache.states.info(i, f.chainState[i]);
        if (st.origin != ChainStateOrigin::LearntOnline) continue;
        // Checked only against chains whose own states are beyond doubt.
        bool othersSure = true;
        for (unsigned k = 1; k < nRx; ++k)
            if (k != i) othersSure = othersSure && cache.states.info(k, f.chainState[k]).confirmed;
        if (othersSure)
        {
            double coherence = 0;
            const std::complex<double> z = b.residual(i, b.best(nRx, int(i)), nRx, coherence);
            cache.states.addVerificationEvidence(i, f.chainState[i], z, coherence * coherence);
            // This frame's own assignment: a clear residual beyond what the state's frames
            // scatter by says it may be in another state (the delay classifier lags a switch
            // and multipath moves a delay): the bearing may be off by what correcting the
            // residual would move it.
            const double residual = std::arg(z);
            if (coherence >= opts.learnCoherence && std::abs(residual) > opts.disagreement_rad)
            {
                if (std::isnan(theta0)) theta0 = b.best(nRx, -1);
                const double corrected = b.best(nRx, -1, int(i), -residual);
                f.stateDoubt_rad = std::max(
                    f.stateDoubt_rad, std::abs(std::remainder(corrected - theta0, 2 * M_PI)));
            }
        }
        const ChainStateInfo& now = cache.states.info(i, f.chainState[i]);
        if (now.confirmed || !(now.phaseDoubt_rad > 0)) continue;
        // The doubt as a bearing: how far the whole array's peak moves when this chain's phase
        // is off by the doubt either way.
        if (std::isnan(theta0)) theta0 = b.best(nRx, -1);
        for (const double sign : {-1.0, 1.0})
        {
            const double shifted = b.best(nRx, -1, int(i), sign * now.phaseDoubt_rad);
            f.stateDoubt_rad =
                std::max(f.stateDoubt_rad, std::abs(std::remainder(shifted - theta0, 2 * M_PI)));
        }
    }
}

void CsiPreprocessor::learnChainState(ChannelCache& cache, const CleanCsi& f, unsigned chain)
{
    // The other chains must all be corrected for the bearing to mean anything.
    for (unsigned i = 1; i < f.nRx; ++i)
        if (i != chain && !cache.states.info(i, f.chainState[i]).resolved()) return;
    const SubcarrierLayout& layout = *f.layout;
    const size_t nSub = layout.size();
    const auto steering = [&](unsigned i, double theta, size_t j)
    {
        const double p = 2 * M_PI * rxArray_.projection(i, theta) / kSpeedOfLightMps;
        return std::polar(1.0, -p * layout.frequencies_Hz[j]);  // conj(a_i(θ, f_j))
    };
    // Wideband Bartlett of the other chains: 1° grid, then 0.05° around the best.
    const auto power = [&](double theta)
    {
        double sum = 0;
        for (unsigned m = 0; m < f.nTx; ++m)
            for (size_t j = 0; j < nSub; ++j)
            {
                std::complex<double> acc{0, 0};
                for (unsigned i = 0; i < f.nRx; ++i)
                    if (i != chain)
                        acc += std::complex<double>(
                                   f.H(Eigen::Index(m * f.nRx + i), Eigen::Index(j))) *
                               steering(i, theta, j);
                sum += std::norm(acc);
            }
        return sum;
    };
    const double best = peakBearing(rxArray_, power, M_PI / 3600);
    std::complex<double> z{0, 0};
    for (unsigned m = 0; m < f.nTx; ++m)
        for (size_t j = 0; j < nSub; ++j)
        {
            std::complex<double> others{0, 0};
            for (unsigned i = 0; i < f.nRx; ++i)
                if (i != chain)
                    others +=
                        std::complex<double>(f.H(Eigen::Index(m * f.nRx + i), Eigen::Index(j))) *
                        steering(i, best, j);
            z += std::complex<double>(f.H(Eigen::Index(m * f.nRx + chain), Eigen::Index(j))) *
                 steering(chain, best, j) * std::conj(others);
        }
    cache.states.addLearningEvidence(chain, f.chainState[chain], z);
}

std::vector<const ChainStateTracker*> CsiPreprocessor::chainStateTrackers() const
{
    std::vector<const ChainStateTracker*> out;
    for (const auto& [key, c] : caches_) out.push_back(&c.states);
    return out;
}

std::vector<std::string> CsiPreprocessor::takeChainStateNotices()
{
    std::vector<std::string> out;
    for (auto& [key, c] : caches_)
        for (auto& n : c.states.takeNotices())
            out.push_back(c.layout->chanspec.asString() + " " + n);
    return out;
}

uint64_t CsiPreprocessor::chainStateChanges() const
{
    uint64_t n = 0;
    for (const auto& [key, c] : caches_) n += c.states.totalChanges();
    return n;
}

std::vector<PhaseCalibration> CsiPreprocessor::calibrationsWithLearntStates(
    bool confirmedOnly) const
{
    std::vector<PhaseCalibration> out;
    for (const auto& [key, c] : caches_)
    {
        if (!c.calibration || !c.states.applies()) continue;
        auto learnt = c.states.learntStates(confirmedOnly);
        if (learnt.empty()) continue;
        PhaseCalibration cal = *c.calibration;
        for (auto& st : learnt) cal.chainStates.push_back(st);
        out.push_back(std::move(cal));
    }
    return out;
}

// ---------------------------------------------------------------------------------------------
CsiWindow::CsiWindow(size_t capacity, double maxAge_s)
    : ring_(std::max<size_t>(capacity, 1)), maxAge_s_(maxAge_s)
{
}

CleanCsi& CsiWindow::slot()
{
    return ring_[head_];
}

void CsiWindow::commit()
{
    const CleanCsi& added = ring_[head_];
    if (count_ > 0)
    {
        const CleanCsi& prev = newest();
        if (prev.layout != added.layout || prev.nRx != added.nRx || prev.nTx != added.nTx ||
            prev.H.rows() != added.H.rows() || added.timestamp < prev.timestamp)
            count_ = 0;  // another shape (or time went back): the old frames don't combine
    }
    head_ = (head_ + 1) % ring_.size();
    count_ = std::min(count_ + 1, ring_.size());
}

const CleanCsi& CsiWindow::newest() const
{
    return ring_[(head_ + ring_.size() - 1) % ring_.size()];
}

void CsiWindow::recent(
    size_t n, std::vector<const CleanCsi*>& out, std::optional<double> maxAge_s) const
{
    out.clear();
    if (count_ == 0) return;
    const auto tNewest = newest().timestamp;
    const double maxAge = std::min(maxAge_s_, maxAge_s.value_or(maxAge_s_));
    n = std::min(n, count_);
    for (size_t back = n; back-- > 0;)
    {
        const CleanCsi& f = ring_[(head_ + ring_.size() - 1 - back) % ring_.size()];
        if (mrpt::system::timeDifference(f.timestamp, tNewest) > maxAge) continue;
        out.push_back(&f);
    }
}

CsiWindow& TransmitterWindows::of(const MacAddress& mac)
{
    auto it = windows_.find(mac);
    if (it == windows_.end()) it = windows_.emplace(mac, CsiWindow(capacity_, maxAge_s_)).first;
    return it->second;
}

}  // namespace mrpt_wifi
