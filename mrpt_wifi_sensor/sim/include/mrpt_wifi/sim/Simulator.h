/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/core/Clock.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/sim/ChannelModel.h>
#include <mrpt_wifi/sim/CsiSynthesizer.h>
#include <mrpt_wifi/sim/Impairments.h>
#include <mrpt_wifi/sim/Scenario.h>
#include <mrpt_wifi/sim/Trajectory.h>

#include <limits>
#include <optional>
#include <ostream>
#include <vector>

namespace mrpt_wifi::sim
{
/** What really happened for one CSI frame. Angles in radians. */
struct FrameTruth
{
    size_t transmitterIndex = 0;
    uint64_t frameIndex = 0;  //!< n-th frame of that transmitter since t = 0
    /** 0: the frame's first reception; 1: its 802.11 retry (impairments.retryProbability). */
    unsigned reception = 0;
    uint16_t sequenceNumber = 0;
    double time_s = 0;               //!< since the scenario start
    mrpt::math::TPose2D robotPose;   //!< world frame, robot base
    mrpt::math::TPose2D sensorPose;  //!< world frame, receive array
    /** Geometric line-of-sight direction towards the transmitter, sensor frame (AoA). */
    double aoa_rad = 0;
    /** Geometric line-of-sight direction towards the receive array, transmitter frame (AoD). */
    double aod_rad = 0;
    double losDistance_m = 0;
    double losDelay_s = 0;
    double losCrossingLoss_dB = 0;  //!< > 0 when obstacles/walls attenuate the line of sight
    /** Line-of-sight power over the power of all other paths (Rician K) [dB]. */
    double kFactor_dB = 0;
    double strongestPathAoa_rad = 0;  //!< sensor frame; differs from aoa_rad when LoS is weak
    unsigned pathCount = 0;
    double rxPower_dBm = 0;  //!< received signal power (link budget)
    double snr_dB = 0;       //!< wideband SNR the noise was drawn for
    int8_t rssi_dBm = 0;     //!< what the frame reports
    PacketImpairments packet;
};

/** One item of the simulated stream. */
struct SimEvent
{
    enum class Kind : uint8_t
    {
        Odometry,
        Csi
    };
    Kind kind = Kind::Csi;
    double time_s = 0;                              //!< since the scenario start
    mrpt::math::TPose2D truePose;                   //!< robot base at time_s, world frame
    mrpt::obs::CObservationOdometry::Ptr odometry;  //!< Kind::Odometry
    CObservationWiFiCSI::Ptr csi;                   //!< Kind::Csi
    FrameTruth frame;                               //!< Kind::Csi
};

/** Turns a Scenario into a time-ordered stream of odometry and CSI observations with ground
 *  truth, as a real recording of the robot would be.
 *
 * Reproducible: every frame is a pure function of (seed, boot, transmitter, frame index), so
 * filtering channels, rewinding or skipping never changes what a given frame contains.
 * Not thread-safe; use one Simulator per thread. */
class Simulator
{
public:
    /** Validates the scenario (throws ScenarioError) and precomputes trajectory, odometry,
     *  transmitter images and the receiver hardware of boot 0. */
    explicit Simulator(Scenario scenario);

    const Scenario& scenario() const { return sc_; }
    const Trajectory& trajectory() const { return trajectory_; }
    const std::vector<OdometrySample>& odometry() const { return odometry_; }
    double duration() const { return sc_.duration_s; }
    /** Recording timestamp of a simulation time. */
    mrpt::Clock::time_point timestampAt(double t_s) const;

    /** Next event in time order (odometry before frames at equal times, then transmitter
     *  order). Returns false at the end of the scenario. Reuses `ev.csi` / `ev.odometry` when
     *  the caller holds no other reference to them. */
    bool next(SimEvent& ev);

    /** Only transmitters on this channel (same centre channel and bandwidth) produce frames;
     *  the others fall silent, as for a receiver tuned elsewhere. nullopt: all of them.
     *  The caller then tunes the receiver (the emulator does, by router command): the
     *  scenario's receiver channel schedule no longer applies, with or without a filter. */
    void setChannelFilter(std::optional<Chanspec> cs)
    {
        channelFilter_ = cs;
        followSchedule_ = false;
    }
    const std::optional<Chanspec>& channelFilter() const { return channelFilter_; }
    /** Odometry events on/off (the emulator only needs CSI). */
    void setOdometryEnabled(bool enabled) { odometryEnabled_ = enabled; }

    /** Restarts the stream at time t (events at or after t). */
    void rewind(double t_s = 0);

    /** A router reboot: new per-chain phase offsets and jump timeline (boot index + 1). */
    void reboot();
    const HardwareModel& hardware() const { return hardware_; }
    /** A reboot of transmitter tx: new transmit-chain phases and gains (its boot index + 1). */
    void rebootTransmitter(size_t tx);
    /** Transmit chains of transmitter tx (its current boot). */
    const TransmitterHardware& transmitterHardware(size_t tx) const { return tx_.at(tx).hardware; }

    /** Time of frame n of transmitter tx (periodic with jitter < one period). */
    double frameTime(size_t tx, uint64_t n) const;
    /** Index of the first frame of `tx` at or after time t. */
    uint64_t firstFrameAtOrAfter(size_t tx, double t_s) const;

    /** Synthesizes frame n of transmitter tx into `out` (reusing its storage) with its truth;
     *  `reception` 1: its 802.11 retry (same sequence number, retryDelay() later, its own
     *  noise, sampling-time offset and CFO). Independent of the stream position and the
     *  channel filter. */
    void synthesizeFrame(
        size_t tx, uint64_t n, CObservationWiFiCSI& out, FrameTruth& truth, unsigned reception = 0);
    /** How long after frame n of tx its retry arrives [s], or a negative value when it has
     *  none. */
    double retryDelay(size_t tx, uint64_t n) const;

    /** Paths of the current geometry for a transmitter and robot pose (for tests/plots). */
    std::vector<PropagationPath> pathsAt(size_t tx, const mrpt::math::TPose2D& robotPose) const;

    /** World pose of the receive array for a robot pose. */
    mrpt::math::TPose2D sensorPoseInWorld(const mrpt::math::TPose2D& robotPose) const;

    /** True impairments of the current boot for every channel in the scenario, as JSON. */
    void writeImpairmentsJson(std::ostream& o) const;

private:
    struct TransmitterState
    {
        ChannelModel::ImageSet images;
        double framePeriod_s = 0;
        double phase_s = 0;      //!< time of frame 0
        uint64_t nextFrame = 0;  //!< stream position
        /** The retry of frame retryFrame due at retryTime_s (infinity: none pending). */
        double retryTime_s = std::numeric_limits<double>::infinity();
        uint64_t retryFrame = 0;
        TransmitterHardware hardware;
    };

    /** Whether the receiver, given the channel filter, hears transmitter tx. */
    bool hears(size_t tx) const;
    /** With a receiver schedule: moves tx's next frame to the first one the receiver hears
     *  (listening on its channel, not switching); false if none is left in the scenario. */
    bool skipToHeardFrame(size_t tx);
    /** Whether a frame of tx arriving at t_s is heard under the receiver schedule. */
    bool heardAt(size_t tx, double t_s) const;

    Scenario sc_;
    ChannelModel channel_;
    Trajectory trajectory_;
    std::vector<OdometrySample> odometry_;
    std::vector<TransmitterState> tx_;
    HardwareModel hardware_;
    CsiSynthesizer synthesizer_;
    std::optional<Chanspec> channelFilter_;
    bool followSchedule_ = true;  //!< receiver.channelSchedule applies (no channel filter set)
    bool odometryEnabled_ = true;
    size_t nextOdometry_ = 0;
    double streamTime_ = 0;  //!< time of the last event returned by next()

    // Per-frame workspaces (no allocation once grown).
    std::vector<PropagationPath> paths_;
    std::vector<std::complex<float>> ideal_;
    std::vector<std::complex<float>> rxFactors_;
    std::vector<std::complex<float>> txScratch_;
    std::vector<std::complex<float>> intelScratch_;
    /** ReceiverSpec::csiFormat Intel5300: keep the grouped subcarriers, quantise to int8. */
    void toIntel5300(CObservationWiFiCSI& out);
    std::vector<uint32_t> noiseTableRe_, noiseTableIm_;  // float bits, see Simulator.cpp
    std::vector<uint32_t> noiseScratchRe_, noiseScratchIm_;
};

}  // namespace mrpt_wifi::sim
