/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/ChainStates.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace mrpt_wifi
{
/** Writes each frame's receive-chain delays and jump states onto the observation
 *  (CObservationWiFiCSI::chainDelay_ns / chainState) as a recorder sees them: the live sensor
 *  uses it on every delivered frame, so a rawlog shows the states in RawLogViewer and the
 *  status line counts the changes.
 *
 *  The classifier is the bearing chain's (ChainStateTracker, one per channel and chain count),
 *  on the same subcarriers; with a calibration store its state ids are the calibration's.
 *  Estimators classify again from the CSI: what is recorded is for people and tools, not an
 *  input to the bearings. Not thread-safe. */
class ChainStateRecorder
{
public:
    /** `calib` / `device`: the receiver calibration the bearings use (its states give the ids);
     *  empty: ids in the order the states are first seen. */
    explicit ChainStateRecorder(
        ChainStateOptions options = {}, CalibrationStore calib = {}, std::string device = {});

    /** Fills the frame's chain fields (left empty for a single-chain frame, a frame with no
     *  complete stream, or a bandwidth without a data-subcarrier plan). */
    void record(CObservationWiFiCSI& frame);

    /** State changes seen, over every channel and chain. */
    uint64_t changes() const;
    /** Chains seen in more than one state, over every channel. */
    size_t chainsWithJumps() const;
    /** One block per channel: the trackers' summaries. */
    std::string summary() const;
    /** The trackers' notices (a state the calibration lacks), taken once. */
    std::vector<std::string> takeNotices();

private:
    ChainStateOptions options_;
    CalibrationStore calib_;
    std::string device_;
    CsiPreprocessor layouts_;  //!< only for its subcarrier layouts (cached per channel)
    std::map<std::pair<const SubcarrierLayout*, unsigned>, ChainStateTracker> trackers_;
    std::map<std::pair<const SubcarrierLayout*, unsigned>, std::string> channelNames_;
    std::vector<double> delays_s_, coherence_;  //!< scratch
    std::vector<uint8_t> ids_;
};

}  // namespace mrpt_wifi
