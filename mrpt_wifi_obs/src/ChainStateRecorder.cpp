/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt_wifi/obs/ChainStateRecorder.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi
{
ChainStateRecorder::ChainStateRecorder(
    ChainStateOptions options, CalibrationStore calib, std::string device)
    : options_(options), calib_(std::move(calib)), device_(std::move(device))
{
}

void ChainStateRecorder::record(CObservationWiFiCSI& frame)
{
    frame.chainDelay_ns.clear();
    frame.chainState.clear();
    if (frame.nRx < 2) return;
    std::shared_ptr<const SubcarrierLayout> layout;
    try
    {
        layout = layouts_.layoutFor(frame);
    }
    catch (const std::invalid_argument&)
    {
        return;  // no data-subcarrier plan: nothing to measure the delays on
    }
    if (!measureChainDelays(frame, *layout, delays_s_, coherence_)) return;

    const auto key = std::make_pair(layout.get(), unsigned(frame.nRx));
    auto it = trackers_.find(key);
    if (it == trackers_.end())
    {
        const PhaseCalibration* cal = nullptr;
        try
        {
            if (!calib_.empty()) cal = calib_.find(device_, frame.chanspec, frame.nRx);
        }
        catch (const CalibrationError&)
        {
            // Another device or too few antennas: the bearing chain reports it; the recorder
            // still reports the states, with ids of its own.
        }
        it = trackers_
                 .emplace(
                     key, ChainStateTracker(frame.nRx, cal, options_, frame.chanspec.bandwidthMHz))
                 .first;
        channelNames_[key] = frame.chanspec.asString() + ", " + std::to_string(frame.nRx) +
                             " chains" + (cal ? ", calibration " + cal->sourcePath : "");
    }
    it->second.classify(delays_s_, coherence_, ids_);

    frame.chainDelay_ns.resize(delays_s_.size());
    for (size_t i = 0; i < delays_s_.size(); ++i)
        frame.chainDelay_ns[i] = i > 0 && coherence_[i] < options_.minCoherence
                                     ? std::numeric_limits<float>::quiet_NaN()
                                     : float(delays_s_[i] * 1e9);
    frame.chainState = ids_;
}

uint64_t ChainStateRecorder::changes() const
{
    uint64_t n = 0;
    for (const auto& [key, t] : trackers_) n += t.totalChanges();
    return n;
}

size_t ChainStateRecorder::chainsWithJumps() const
{
    size_t n = 0;
    for (const auto& [key, t] : trackers_)
        for (unsigned i = 1; i < t.chains(); ++i) n += t.states(i).size() > 1;
    return n;
}

std::string ChainStateRecorder::summary() const
{
    std::ostringstream o;
    for (const auto& [key, t] : trackers_) o << channelNames_.at(key) << ":\n" << t.summary();
    return o.str();
}

std::vector<std::string> ChainStateRecorder::takeNotices()
{
    std::vector<std::string> all;
    for (auto& [key, t] : trackers_)
        for (auto& n : t.takeNotices()) all.push_back(channelNames_.at(key) + ": " + n);
    return all;
}

}  // namespace mrpt_wifi
