/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/core/Clock.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt/obs/CObservation.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/bearing/BearingProcessor.h>

#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace mrpt_wifi
{
/** The `bearing_*` keys of a CWiFiCSISensor section (share/rawlog-grabber/csi_live_bearings.ini
 *  documents them). They mean what the same-named `csi-bearings` options mean. */
struct LiveBearingSettings
{
    std::string algorithm;    //!< bearing_algorithm: a csi-bearings estimator name; empty = off
    std::string calibration;  //!< bearing_calibration: a file or a folder (as --calib)
    std::string arrayFile;    //!< bearing_array: empty = share/arrays/rt-ac86u.yaml
    /** bearing_options: a YAML file as csi-bearings --config, or inline options of the
     *  estimator, `{angle_bins: 90, window: 4}` (as csi-bearings --param). */
    std::string optionsFile;
    std::vector<std::string> txArrays;  //!< bearing_tx_arrays: `[MAC=]FILE`, as --tx-array
    size_t queueLength = 64;            //!< bearing_queue_length: frames waiting, at most
    /** bearing_calibration_max_age_days: an older calibration is reported as stale (the
     *  RT-AC86U's chain phases change at every boot). 0: no age check. */
    double calibrationMaxAge_days = 7;

    bool enabled() const { return !algorithm.empty(); }
};

/** The chain `csi-bearings` builds from the same inputs (estimator, options file, array,
 *  calibration, transmitter arrays). Throws (std::invalid_argument, CalibrationError, ...) with
 *  a message that names the `bearing_*` key at fault. */
std::unique_ptr<bearing::BearingProcessor> makeLiveBearingProcessor(const LiveBearingSettings& s);

/** Bearings computed next to a capture loop: CSI frames are handed over without waiting; one
 *  worker thread runs a bearing::BearingProcessor on them in arrival order. When more than
 *  `queueLength` frames wait, new frames skip the estimation (counted) — capture is never slowed.
 *
 *  Every submitted frame comes back from takeReady() in arrival order once its estimation is done
 *  (or skipped), directly followed by its CObservationWiFiBearing (label `<label>_AOA`) and
 *  CObservationBearingRange, as `csi-bearings` writes them after each CSI observation.
 *
 *  The calibration is checked (missing for the channel, for another channel or device, stale)
 *  for the configured channel at construction and again on the first frame of every channel;
 *  the findings come out of takeMessages(). */
class LiveBearingWorker
{
public:
    struct Stats
    {
        uint64_t submitted = 0;          //!< frames handed over
        uint64_t estimated = 0;          //!< went through the chain
        uint64_t bearings = 0;           //!< gave a bearing
        uint64_t skipped = 0;            //!< the queue was full: no estimation
        uint64_t rejected = 0;           //!< refused by preprocessing (RSSI, streams, ...)
        uint64_t calibrationErrors = 0;  //!< the calibration does not fit the frame
        uint64_t odometry = 0;           //!< odometry readings handed to the chain
    };
    /** Frame complete (submit) → bearing ready, over the frames estimated since the last call. */
    struct Latency
    {
        size_t samples = 0;
        double p50_s = 0, p99_s = 0, max_s = 0;
    };
    struct Message
    {
        bool problem = false;  //!< a warning (false: information)
        std::string text;
    };

    LiveBearingWorker(
        std::unique_ptr<bearing::BearingProcessor> processor, const LiveBearingSettings& settings,
        std::optional<Chanspec> configuredChannel = std::nullopt);
    ~LiveBearingWorker();
    LiveBearingWorker(const LiveBearingWorker&) = delete;
    LiveBearingWorker& operator=(const LiveBearingWorker&) = delete;

    /** Hands a complete frame over (capture thread; never blocks on estimation). */
    void submit(CObservationWiFiCSI::Ptr frame);
    /** Robot odometry (any thread, time order), as csi-bearings gives its chain: a window then
     *  combines only the frames taken near the newest (bearing::BearingProcessor::addOdometry).
     *  Handed to the chain before the next frame's estimation. Without it a window holds the
     *  frames of the last Options::maxWindowSpanWithoutOdometry_s. */
    void addOdometry(mrpt::Clock::time_point t, const mrpt::math::TPose2D& odometry);
    /** Appends the frames that are done, each followed by its bearing observations. */
    void takeReady(std::vector<mrpt::obs::CObservation::Ptr>& out);
    /** Waits (at most `timeout_s`) until every submitted frame is done; true if they are. */
    bool waitIdle(double timeout_s);

    Stats stats() const;
    /** At most this many samples wait for takeLatency() (the newest). */
    static constexpr size_t kMaxLatencySamples = 1u << 16;
    Latency takeLatency();
    std::vector<Message> takeMessages();

    /** What the calibration store holds for a channel: a problem (none for it, another channel
     *  or device, stale) or the file used. Not thread-safe: worker thread or before it starts. */
    static Message describeCalibration(
        bearing::BearingProcessor& processor, const Chanspec& cs, unsigned nRx, double maxAge_days,
        mrpt::Clock::time_point now);

private:
    struct Slot
    {
        CObservationWiFiCSI::Ptr frame;
        mrpt::Clock::time_point submitted;
        bool done = false;
        std::vector<mrpt::obs::CObservation::Ptr> extra;
    };
    void run();
    void estimate(Slot& slot);

    std::unique_ptr<bearing::BearingProcessor> processor_;
    LiveBearingSettings settings_;
    std::optional<uint32_t> lastChannel_;  //!< worker thread only
    /** Channels whose calibration was reported (a channel schedule comes back to each). */
    std::set<uint32_t> reportedChannels_;

    mutable std::mutex mutex_;
    std::condition_variable wake_, idle_;
    std::deque<std::shared_ptr<Slot>> order_;  //!< every submitted frame not yet taken
    std::deque<std::shared_ptr<Slot>> work_;   //!< waiting for estimation
    std::vector<std::pair<mrpt::Clock::time_point, mrpt::math::TPose2D>> odometry_;  //!< not yet
                                                                                     //!< given
    size_t busy_ = 0;  //!< being estimated
    bool stop_ = false;
    Stats stats_;
    std::vector<double> latencies_s_;
    std::vector<Message> messages_;
    std::thread thread_;
};

}  // namespace mrpt_wifi
