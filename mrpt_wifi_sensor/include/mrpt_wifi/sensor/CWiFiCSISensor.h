/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/hwdrivers/CGenericSensor.h>
#include <mrpt/system/COutputLogger.h>
#include <mrpt_wifi/sensor/AccessPointSelector.h>
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>
#include <mrpt_wifi/sensor/CsiLiveSource.h>
#include <mrpt_wifi/sensor/CsiSensorSettings.h>
#include <mrpt_wifi/sensor/NexmonPiControl.h>
#include <mrpt_wifi/sensor/NexmonRouterControl.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

namespace mrpt_wifi
{
class UdpCsiReceiver;
class PcapReader;
class LiveBearingWorker;
class ChainStateRecorder;
namespace bearing
{
class BearingProcessor;
}

/** Captures WiFi CSI from an Asus RT-AC86U running Nexmon CSI firmware, as
 * mrpt_wifi::CObservationWiFiCSI, inside `rawlog-grabber` or any MRPT program.
 *
 * Data path: Nexmon datagrams over UDP (or replayed from a pcap at recorded pace) → header
 * checks → frame assembly → router-address / MAC / RSSI filters → observations stamped with
 * the kernel arrival time of their first datagram.
 * Control path (optional): the router is configured over ssh (firmware module, chanspec,
 * monitor mode, makecsiparams + nexutil), scanned for access points, switched between
 * channels, and put in transmitter mode — in a worker thread, so capture never stalls. Or
 * (`pi_control`) a Raspberry Pi's own chip is configured, here or over ssh (NexmonPiControl).
 *
 * See the .ini files in share/rawlog-grabber/ for every configuration key. Unknown keys are an
 * error. Registered as `driver = CWiFiCSISensor` by libmrpt_wifi_sensor.so. */
class CWiFiCSISensor : public mrpt::hwdrivers::CGenericSensor, public mrpt::system::COutputLogger
{
    DEFINE_GENERIC_SENSOR(CWiFiCSISensor)

public:
    CWiFiCSISensor();
    ~CWiFiCSISensor() override;

    void initialize() override;
    void doProcess() override;

    /** Asks for a retune (asynchronous). The downtime, from this call to the first frame on
     * the new channel, is measured and logged. */
    void requestChannel(const Chanspec& cs, const std::string& reason);
    /** Asks for an access-point scan now (asynchronous); the result is recorded. */
    void requestScan();

    struct Counters
    {
        uint64_t datagrams = 0;         //!< received from the socket / pcap
        uint64_t fromOtherSources = 0;  //!< dropped by the router-address filter
        uint64_t framesDelivered = 0;   //!< appended as observations
        uint64_t framesFilteredMac = 0;
        uint64_t framesFilteredRssi = 0;
        uint64_t kernelDrops = 0;  //!< lost in the socket buffer
        uint64_t scans = 0;
        uint64_t channelSwitches = 0;
        uint64_t controlErrors = 0;
        uint64_t chainStateChanges = 0;  //!< receive-chain jump-state changes (all channels)
        uint64_t chainsWithJumps = 0;    //!< chains seen in more than one state
        /** What hopping among `channel_schedule` costs, per channel visited. */
        struct ChannelUse
        {
            Chanspec chanspec;
            uint64_t visits = 0;         //!< switches to this channel (and the first set-up)
            uint64_t frames = 0;         //!< frames delivered on it
            double time_s = 0;           //!< from each switch request to the next one
            double downtime_s = 0;       //!< from each switch request to its first frame
            uint64_t measured = 0;       //!< visits whose first frame came (downtime known)
            uint64_t withoutFrames = 0;  //!< visits that ended without any frame
            /** Frames the downtime cost, at the rate the channel delivered otherwise. */
            double framesLostEstimate() const;
        };
        std::map<uint32_t, ChannelUse> channels;  //!< key: centre << 16 | bandwidth
        uint64_t scheduleSwitches = 0;            //!< switches made by channel_schedule
        double maxSwitchDowntime_s = 0;
        CsiFrameAssemblerStats assembler;
        /** The first few addresses whose datagrams router_address dropped (what to set it to). */
        std::vector<std::string> otherSourceAddresses;
    };
    Counters counters() const;

    /** Why the data path delivered no frame (wifi-localize's no_csi_timeout_s). */
    struct NoFrameDiagnosis
    {
        enum class Cause
        {
            None,              //!< frames were delivered
            ControlFailed,     //!< configuring the router / Pi failed, and no datagram came
            NoDatagrams,       //!< nothing arrived on the data path
            NoMatchingFrames,  //!< datagrams, but no frame passed the checks and filters
            ReplayEnded        //!< source = pcap reached its end
        };
        Cause cause = Cause::None;
        std::string text;  //!< the cause and what to check, with the keys to change
    };
    /** Compares counters() now with `before` (taken `seconds` ago). */
    NoFrameDiagnosis diagnoseNoFrames(const Counters& before, double seconds) const;
    /** Why the sensor is in the error state (empty when it isn't). */
    std::string lastError() const;
    /** The channel the router was last configured to (nullopt before the first success). */
    std::optional<Chanspec> configuredChannel() const;
    /** Downtime of the last completed channel switch [s]. */
    std::optional<double> lastSwitchDowntime() const;
    /** One line on what hopping among channels cost so far (empty without channel_schedule):
     *  switches, time without CSI per switch, frames lost, frames per channel. Logged with the
     *  status and when the sensor closes. */
    std::string channelScheduleSummary() const;
    /** The channels currently visited in turn (the given list, or the latest scan's). */
    std::vector<Chanspec> channelSchedule() const;
    /** The live bearing estimation (`bearing_algorithm`), or nullptr when it is off or before
     *  initialize(). */
    LiveBearingWorker* bearingWorker() { return bearings_.get(); }

protected:
    void loadConfig_sensorSpecific(
        const mrpt::config::CConfigFileBase& config, const std::string& section) override;

private:
    std::unique_ptr<CsiSensorSettings> settings_;

    // Data path
    std::unique_ptr<UdpCsiReceiver> receiver_;
    std::unique_ptr<PcapReader> replay_;
    std::unique_ptr<CsiLiveSource> live_;  //!< source = interface:IFACE / serial:DEVICE
    std::unique_ptr<CsiFrameAssembler> assembler_;
    mrpt::Clock::time_point replayStartWall_, replayStartCapture_;
    bool replayHasPending_ = false;
    std::vector<uint8_t> replayPending_;
    std::string replayPendingSource_;
    mrpt::Clock::time_point replayPendingTime_;
    std::atomic<bool> replayFinished_{false};
    void onDatagram(
        const uint8_t* data, size_t len, mrpt::Clock::time_point t, const std::string& src);
    void onFrame(CObservationWiFiCSI::Ptr&& frame);
    void drainReplay();
    std::unique_ptr<ChainStateRecorder> chainStates_;  //!< record_chain_states; under mutex_

    // Control path: one worker thread runs router jobs in order; results come back as events.
    std::unique_ptr<NexmonRouterControl> router_;
    std::unique_ptr<NexmonPiControl> pi_;  //!< pi_control = local / ssh
    std::thread worker_;
    std::deque<std::function<void()>> jobs_;
    std::deque<std::function<void()>> events_;  //!< run on the sensor thread
    bool stopWorker_ = false;
    bool scanQueued_ = false;
    mutable std::mutex mutex_;
    std::condition_variable jobReady_;
    void postJob(std::function<void()> job);
    void postEvent(std::function<void()> event);
    void workerLoop();
    void runEvents();
    void reportControlError(const std::string& what);

    // Channel switching
    std::optional<Chanspec> configured_;
    std::optional<Chanspec> switchTarget_;
    mrpt::Clock::time_point switchRequested_;
    std::optional<double> lastSwitchDowntime_;
    std::unique_ptr<AccessPointSelector> selector_;
    mrpt::Clock::time_point lastScan_, lastStatus_;

    // Channel schedule (channel_schedule): one switch in flight at a time; a channel's dwell
    // starts when the router confirms the switch.
    std::vector<Chanspec> schedule_;
    bool hopInFlight_ = false;
    mrpt::Clock::time_point dwellStart_, visitStart_;
    std::optional<Chanspec> visiting_;  //!< the channel the current visit's time goes to
    bool visitIsSwitch_ = false;        //!< false for the start-up configuration
    void onChannelConfigured(const Chanspec& cs);
    void advanceSchedule(mrpt::Clock::time_point now);
    void startVisit(const Chanspec& cs, mrpt::Clock::time_point t);  //!< under mutex_

    // Live bearings (bearing_* keys): frames go through the worker, which returns them in order
    // followed by their bearing observations.
    std::unique_ptr<bearing::BearingProcessor> bearingProcessor_;  //!< built by loadConfig
    std::unique_ptr<LiveBearingWorker> bearings_;
    uint64_t bearingsAtLastStatus_ = 0, skippedAtLastStatus_ = 0;
    mrpt::Clock::time_point bearingStatusTime_;
    void startBearings();
    void deliverBearings();
    std::string bearingStatus();

    Counters counters_;
    std::string lastError_;
    void logStatus();
};

}  // namespace mrpt_wifi
