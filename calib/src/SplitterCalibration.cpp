/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/calib/SplitterCalibration.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <sstream>

namespace mrpt_wifi::calib
{
namespace
{
std::string degrees(double rad)
{
    std::ostringstream o;
    o.setf(std::ios::fixed);
    o.precision(1);
    o << rad * 180 / M_PI << " deg";
    return o.str();
}

std::string elementList(const AntennaArray& a, const std::vector<unsigned>& elements)
{
    std::string e, c;
    for (size_t i = 0; i < elements.size(); ++i)
    {
        e += (i ? ", " : "") + std::to_string(elements[i]);
        c += (i ? ", " : "") + std::to_string(a.coreOf(elements[i]));
    }
    return "elements " + e + " (cores " + c + ")";
}
}  // namespace

std::string describeElement(const AntennaArray& a, unsigned element)
{
    return "element " + std::to_string(element) + " (core " + std::to_string(a.coreOf(element)) +
           ")";
}

std::vector<double> splitterFlatness(const CalibrationFrame& f)
{
    std::vector<double> out(f.nRx, 0.0);
    if (!f.layout || f.nRx < 2) return out;
    const auto& k = f.layout->subcarriers;
    const Eigen::Index nSub = f.H.cols();
    Eigen::MatrixXcf z = Eigen::MatrixXcf::Zero(1, nSub);
    for (unsigned i = 1; i < f.nRx; ++i)
    {
        z.setZero();
        for (unsigned m = 0; m < f.nTx; ++m)
            z.row(0) += f.H.row(Eigen::Index(m * f.nRx + i))
                            .cwiseProduct(f.H.row(Eigen::Index(m * f.nRx)).conjugate());
        const double slope = CsiPreprocessor::estimatePhaseSlope(z, k);
        // Without the delay, the phases' circular mean and their RMS spread around it.
        std::vector<std::complex<double>> u(static_cast<size_t>(nSub));
        std::complex<double> mean{0, 0};
        for (Eigen::Index j = 0; j < nSub; ++j)
        {
            const std::complex<double> v =
                std::complex<double>(z(0, j)) * std::polar(1.0, -slope * k[size_t(j)]);
            u[size_t(j)] = std::abs(v) > 0 ? v / std::abs(v) : std::complex<double>(0, 0);
            mean += u[size_t(j)];
        }
        double sum = 0;
        for (const auto& v : u)
        {
            const double r = std::arg(v * std::conj(mean));
            sum += r * r;
        }
        out[i] = nSub > 0 ? std::sqrt(sum / double(nSub)) : 0.0;
    }
    return out;
}

void SplitterFeedDetector::add(const CalibrationFrame& f)
{
    const std::vector<double> flat = splitterFlatness(f);
    if (flatness_.size() < flat.size()) flatness_.resize(flat.size());
    for (size_t i = 1; i < flat.size(); ++i) flatness_[i].push_back(float(flat[i]));
    ++frames_;
}

std::vector<double> SplitterFeedDetector::medianFlatness() const
{
    std::vector<double> out(flatness_.size(), 0.0);
    for (size_t i = 1; i < flatness_.size(); ++i)
    {
        std::vector<float> v = flatness_[i];
        if (v.empty()) continue;
        std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
        out[i] = v[v.size() / 2];
    }
    return out;
}

SplitterFeedDetector::Verdict SplitterFeedDetector::decide() const
{
    Verdict v;
    v.flatness = medianFlatness();
    if (v.flatness.size() < 2) return v;
    const double best = *std::min_element(v.flatness.begin() + 1, v.flatness.end());
    if (!(best <= kMaxFedFlatness)) return v;  // no element is fed with element 0
    // The chains' own ripple sets the fed elements' level; a floor keeps noise-free
    // simulations from calling a fed element with 1e-6 rad more ripple unfed.
    const double level = std::max(best, 0.002);
    v.fed.push_back(0);
    for (unsigned i = 1; i < v.flatness.size(); ++i)
    {
        const double f = v.flatness[i];
        if (f <= kFedRatio * level)
            v.fed.push_back(i);
        else if (f < kUnfedRatio * level && f <= kMaxFedFlatness)
            v.undecided.push_back(i);
    }
    return v;
}

AntennaArray subArray(const AntennaArray& a, const std::vector<unsigned>& elements)
{
    AntennaArray s = a;
    s.elements.clear();
    s.cores.clear();
    for (unsigned e : elements)
    {
        s.elements.push_back(a.elements.at(e));
        s.cores.push_back(a.coreOf(e));
    }
    return s;
}

void restrictFrame(
    const CalibrationFrame& in, const std::vector<unsigned>& elements, CalibrationFrame& out)
{
    out = in;
    const auto n = unsigned(elements.size());
    out.nRx = n;
    out.H.resize(Eigen::Index(in.nTx * n), in.H.cols());
    for (unsigned m = 0; m < in.nTx; ++m)
        for (unsigned r = 0; r < n; ++r)
            out.H.row(Eigen::Index(m * n + r)) = in.H.row(Eigen::Index(m * in.nRx + elements[r]));
    out.chainDelay_s.clear();
    out.chainState.clear();
    for (unsigned e : elements)
    {
        if (e < in.chainDelay_s.size()) out.chainDelay_s.push_back(in.chainDelay_s[e]);
        if (e < in.chainState.size()) out.chainState.push_back(in.chainState[e]);
    }
}

namespace
{
/** The phase [rad] a chain shows in one of its states at subcarrier index j (what the
 *  calibration undoes): φ(k) − 2π·k·Δf·Δd + Δψ. */
double phaseInState(
    const PhaseCalibration& c, unsigned row, size_t j, const ChainStateCalibration* st)
{
    double p = c.phases_rad.at(row).at(j);
    if (st)
        p += -2 * M_PI * kSubcarrierSpacingHz * st->deltaDelay_s * c.subcarriers[j] +
             st->deltaPhase_rad;
    return p;
}

size_t rowOf(const SplitterCapture& c, unsigned element)
{
    return size_t(std::find(c.elements.begin(), c.elements.end(), element) - c.elements.begin());
}
}  // namespace

PhaseCalibration mergeSplitterCaptures(
    const std::vector<SplitterCapture>& captures, const AntennaArray& array,
    double maxDisagreement_rad, std::vector<SplitterMergeNote>* notes)
{
    if (captures.empty()) throw SplitterError("no splitter capture to merge");
    for (const auto& c : captures)
    {
        if (c.elements.size() < 2 || c.elements.front() != 0)
            throw SplitterError(
                "the capture '" + c.name + "' does not feed " + describeElement(array, 0) +
                " together with another element: every capture must feed element 0, the "
                "reference the other chains (and their jump states) are measured against");
        if (c.result.calibration.subcarriers != captures.front().result.calibration.subcarriers)
            throw SplitterError(
                "the captures '" + captures.front().name + "' and '" + c.name +
                "' are on different subcarriers (" +
                captures.front().result.calibration.chanspec.asString() + ", " +
                c.result.calibration.chanspec.asString() + ")");
    }
    const PhaseCalibration& first = captures.front().result.calibration;
    const size_t nSub = first.subcarriers.size();
    const auto n = unsigned(array.size());

    PhaseCalibration out;
    out.device = array.name;
    out.chanspec = first.chanspec;
    out.date = first.date;
    out.subbandSignCorrected = true;
    out.subcarriers = first.subcarriers;
    out.chainStateTolerance_s = first.chainStateTolerance_s;
    out.phases_rad.assign(n, std::vector<double>(nSub, 0.0));
    out.gains_dB.assign(n, 0.0);
    std::string sources;
    for (const auto& c : captures)
    {
        out.framesUsed += c.result.calibration.framesUsed;
        out.residual_rad = std::max(out.residual_rad, c.result.calibration.residual_rad);
        sources += (sources.empty() ? "" : "; ") + c.name + ": " + elementList(array, c.elements);
    }
    out.method = "wifi-calibrate splitter, " + std::to_string(captures.size()) +
                 " capture(s) against element 0 (per-subcarrier PCA + Ceres LM): " + sources;

    for (unsigned e = 1; e < n; ++e)
    {
        std::vector<const SplitterCapture*> feeding;
        for (const auto& c : captures)
            if (rowOf(c, e) < c.elements.size()) feeding.push_back(&c);
        if (feeding.empty())
        {
            std::string what;
            for (const auto& c : captures)
                what += "\n  " + c.name + ": " + elementList(array, c.elements);
            throw SplitterError(
                describeElement(array, e) + " is fed by no capture, so it has no offset; " +
                "record one more with the splitter on core " + std::to_string(array.coreOf(e)) +
                " and core " + std::to_string(array.coreOf(0)) + ". The captures feed:" + what);
        }
        const SplitterCapture* best = feeding.front();
        for (const auto* c : feeding)
            if (c->result.calibration.framesUsed > best->result.calibration.framesUsed) best = c;
        const PhaseCalibration& bc = best->result.calibration;
        const auto br = unsigned(rowOf(*best, e));

        SplitterMergeNote note;
        note.element = e;
        note.from = best->name;
        for (const auto* c : feeding)
        {
            if (c == best) continue;
            const PhaseCalibration& oc = c->result.calibration;
            const auto orow = unsigned(rowOf(*c, e));
            // Compare in a jump state both saw (their reference states may differ).
            const ChainStateCalibration *sb = nullptr, *so = nullptr;
            uint64_t shared = 0;
            const double tol = std::max(bc.chainStateTolerance_s, oc.chainStateTolerance_s);
            for (const auto& a : bc.chainStates)
                for (const auto& b : oc.chainStates)
                    if (a.antenna == br && b.antenna == orow &&
                        std::abs(a.delay_s - b.delay_s) <= tol &&
                        std::min(a.frames, b.frames) >= shared)
                        sb = &a, so = &b, shared = std::min(a.frames, b.frames);
            bool bestHasStates = false, otherHasStates = false;
            for (const auto& a : bc.chainStates) bestHasStates |= a.antenna == br;
            for (const auto& b : oc.chainStates) otherHasStates |= b.antenna == orow;
            if (!sb && bestHasStates && otherHasStates)
                throw SplitterError(
                    "the captures '" + best->name + "' and '" + c->name + "' both feed " +
                    describeElement(array, e) +
                    " but saw it in no common jump state, so their offsets can't be compared; "
                    "feed each chain in one capture only, or record longer");
            std::complex<double> diff{0, 0};
            for (size_t j = 0; j < nSub; ++j)
                diff +=
                    std::polar(1.0, phaseInState(bc, br, j, sb) - phaseInState(oc, orow, j, so));
            const double d = std::abs(std::arg(diff));
            if (d > maxDisagreement_rad)
                throw SplitterError(
                    "the captures '" + best->name + "' and '" + c->name + "' disagree on " +
                    describeElement(array, e) + " by " + degrees(d) + " (limit " +
                    degrees(maxDisagreement_rad) +
                    "): a cable or the splitter changed between them, or the router rebooted");
            note.agreeing.push_back(c->name);
            note.maxDisagreement_rad = std::max(note.maxDisagreement_rad, d);
        }
        out.phases_rad[e] = bc.phases_rad.at(br);
        if (!bc.gains_dB.empty()) out.gains_dB[e] = bc.gains_dB.at(br);
        for (const auto& st : bc.chainStates)
            if (st.antenna == br)
            {
                ChainStateCalibration s = st;
                s.antenna = e;
                out.chainStates.push_back(s);
            }
        if (notes) notes->push_back(note);
    }
    out.validate("merged splitter calibration of " + out.chanspec.asString());
    return out;
}

}  // namespace mrpt_wifi::calib
