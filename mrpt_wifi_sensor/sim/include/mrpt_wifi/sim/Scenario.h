/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPoint2D.h>
#include <mrpt/math/TPose2D.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/obs/MacAddress.h>
#include <mrpt_wifi/sim/AntennaArray.h>

#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

/** Radio channel simulator: scenes, wideband CSI synthesis, hardware impairments, robot motion. */
namespace mrpt_wifi::sim
{
/** A scenario file problem, located: "FILE:LINE: key.path: message". */
class ScenarioError : public std::runtime_error
{
public:
    ScenarioError(
        const std::string& file, int line, const std::string& keyPath, const std::string& message);

    const std::string& file() const { return file_; }
    int line() const { return line_; }                       //!< 1-based; 0 when unknown
    const std::string& keyPath() const { return keyPath_; }  //!< e.g. "transmitters[1].channel"
    const std::string& message() const { return message_; }

private:
    std::string file_, keyPath_, message_;
    int line_ = 0;
};

/** A reflecting wall segment (2-D, world frame). */
struct Wall
{
    std::string name;
    mrpt::math::TPoint2D from, to;
    /** Complex amplitude reflection coefficient (|Γ| ≤ 1). */
    std::complex<double> reflection{-0.5, 0.0};
    /** Loss of a ray that crosses the wall instead of reflecting on it [dB]. */
    double transmissionLoss_dB = 12.0;
};

/** A thin obstacle that attenuates every ray crossing it and reflects nothing (a shelf,
 *  a person, a cabinet seen edge-on). */
struct Obstacle
{
    std::string name;
    mrpt::math::TPoint2D from, to;
    double attenuation_dB = 10.0;
};

/** An isotropic point scatterer (a pillar, a machine): bistatic radar cross-section. */
struct Scatterer
{
    std::string name;
    mrpt::math::TPoint2D position;
    double radarCrossSection_m2 = 1.0;
    double phase_rad = 0.0;  //!< extra phase of the scattered wave
};

/** A device whose frames the robot overhears (access point, IoT device, phone). */
struct TransmitterSpec
{
    std::string name;
    MacAddress mac;
    mrpt::math::TPose2D pose;  //!< array origin and boresight (yaw) in the world frame
    Chanspec chanspec;
    unsigned streams = 1;  //!< spatial streams; stream m leaves from array element m
    AntennaArray array = AntennaArray::singleElement();
    double frameRate_Hz = 100.0;
    double txPower_dBm = 20.0;
    double antennaGain_dBi = 2.0;
    uint16_t firstSequenceNumber = 0;  //!< 802.11 sequence number of frame 0
};

/** The robot's receiver: array, where it sits on the robot, front-end noise. */
/** What the simulated receiver reports, as a real capture would arrive. */
enum class CsiFormat : uint8_t
{
    Nexmon = 0,    //!< every bin of the bandwidth (BCM4366c0 / Nexmon)
    Intel5300 = 1  //!< 30 grouped subcarriers (htGroupedSubcarriers), int8 I/Q, source "iwl5300"
};
const char* toString(CsiFormat f);

struct ReceiverSpec
{
    std::string sensorLabel = "WIFI_CSI";
    /** Intel5300: the CSI is kept on the 802.11n grouped subcarriers only (Ng = 2 at 20 MHz,
     *  Ng = 4 at 40 MHz; listed in subcarrierIndices, other bins zero), quantised to int8 I/Q at
     *  an RMS of 20 per component pair like the CSI Tool's values; 20/40 MHz, ≤ 3 antennas. */
    CsiFormat csiFormat = CsiFormat::Nexmon;
    AntennaArray array;
    /** Array pose on the robot; the simulation is planar and uses x, y, yaw (z is kept). */
    mrpt::poses::CPose3D sensorPose;
    double noiseFigure_dB = 7.0;
    double antennaGain_dBi = 2.0;
    uint16_t chipId = 0x006a;  //!< BCM4366c0
    /** The robot's own body (chassis, mast, a laptop) shadows the receive antennas from one
     *  side: every path arriving within ±halfWidth of `center` (sensor frame) loses
     *  attenuation_dB, with a 10° raised-cosine edge. attenuation_dB = 0: no body. */
    struct BodyShadow
    {
        double center_rad = M_PI;
        double halfWidth_rad = 0;
        double attenuation_dB = 0;
        /** Loss [dB] of a ray arriving from `aoa_rad` (sensor frame). */
        double loss_dB(double aoa_rad) const;
    } bodyShadow;

    /** Channel hopping, as CWiFiCSISensor's `channel_schedule`: from t = 0 the receiver
     *  listens to channelSchedule[k] for channelDwell_s, then retunes for channelSwitch_s
     *  (hears nothing), then takes the next channel, cyclically. It hears only transmitters on
     *  the channel it listens to. Empty: every transmitter at once (no tuning modelled); one
     *  channel: it stays there, no switch. */
    std::vector<Chanspec> channelSchedule;
    double channelDwell_s = 2.0;
    double channelSwitch_s = 0.020;  //!< as rt-ac86u-emulator's --retune-delay default

    /** Earliest time ≥ t_s at which the receiver listens to channel `cs` (t_s itself while it
     *  does; +infinity if it never does). Without a schedule: t_s. */
    double nextListeningTime(const Chanspec& cs, double t_s) const;
};

enum class MotionType : uint8_t
{
    Static,     //!< stays at the start pose
    Waypoints,  //!< drives through the waypoints once, then stops
    Loop,       //!< drives through the waypoints cyclically
    RandomWalk  //!< drives to random goals within a disc
};
const char* toString(MotionType t);

struct MotionSpec
{
    MotionType type = MotionType::Static;
    mrpt::math::TPose2D start;  //!< world frame, yaw in radians
    std::vector<mrpt::math::TPoint2D> waypoints;
    double speed_mps = 0.5;
    double turnRate_radps = 1.0;  //!< maximum |ω|
    double goalTolerance_m = 0.1;
    mrpt::math::TPoint2D randomWalkCenter;  //!< defaults to the start position
    double randomWalkRadius_m = 5.0;
    double timeStep_s = 0.01;  //!< integration step of the ground truth
    /** At every goal or waypoint reached the robot stops for a time drawn uniformly in
     *  [0, dwellMax_s] (0: never stops), as a robot that pauses at random poses. */
    double dwellMax_s = 0.0;
};

/** Wheel odometry error model. Per step of length d [m] and rotation Δθ [rad] the reported
 *  increment is: forward ·(1+scaleError) + N(0, σ_xy²·d), lateral + N(0, σ_xy²·d),
 *  Δθ·(1+yawScaleError) + yawDrift·d + N(0, σ_yaw²·d + σ_yawRot²·|Δθ|). */
struct OdometrySpec
{
    bool enabled = true;
    std::string sensorLabel = "ODOMETRY";
    double rate_Hz = 20.0;
    double sigmaXY_m_per_sqrt_m = 0.01;
    double sigmaYaw_rad_per_sqrt_m = 0.005;
    double sigmaYaw_rad_per_sqrt_rad = 0.01;
    double scaleError = 0.0;
    double yawScaleError = 0.0;
    double yawDrift_rad_per_m = 0.0;
    bool startAtOrigin = true;  //!< odometry frame starts at (0,0,0), as on a real robot
};

/** Hardware impairments, each reproducible from the scenario seed (DESIGN.md §5). */
struct ImpairmentSpec
{
    // Fixed per boot, per channel, per receive chain: what calibration must recover.
    bool antennaPhaseOffsets = true;    //!< uniform in [−π, π) per chain and channel
    double antennaGainSigma_dB = 0.5;   //!< per chain gain mismatch
    double rippleAmplitude_rad = 0.08;  //!< RMS of the smooth per-subcarrier phase ripple
    unsigned rippleComponents = 3;      //!< cosine terms across the band
    /** The chains' phase offsets follow their delays from channel to channel: on channel c
     *  chain i's offset is φ_i − 2π·(f_c − f_ref)·τ_i, φ_i the (uniform) offset on the
     *  reference channel, τ_i the chain's delay (cables, filters; fixed per device, every
     *  boot), N(0, `chain_delay_sigma_ns`) unless listed (`chain_delays_ns`). Unset reference
     *  (`chain_phase_reference`; the first transmitter's channel by default): offsets drawn
     *  anew on every channel. The in-band slope of τ is left to the ripple. */
    std::optional<Chanspec> chainPhaseReference;
    double chainDelaySigma_s = 1e-9;
    std::vector<double> chainDelays_s;  //!< per chain; empty: drawn

    // Fixed per transmitter, per boot of that transmitter, per channel, per transmit chain
    // (multi-stream transmitters only): what transmit-chain calibration must recover, and
    // what AoD does not survive without it (DESIGN.md §5).
    bool txChainPhaseOffsets = true;   //!< uniform in [−π, π) per transmit chain and channel
    double txChainGainSigma_dB = 0.5;  //!< per transmit chain gain mismatch
    /** 802.11ac VHT-LTF cyclic shift per space-time stream (0, −400, −200, −600, −350, −650,
     *  −100, −750 ns): a linear phase over the subcarriers, per stream. */
    bool cyclicShiftDelays = true;

    // Per packet.
    double samplingTimeOffsetSigma_s = 25e-9;  //!< linear phase across subcarriers (all chains)
    bool cfoCommonPhase = true;                //!< uniform common phase per packet
    double agcTarget = 1.0;            //!< RMS CSI magnitude the AGC aims at (hardware units)
    double agcSigma_dB = 1.0;          //!< packet-to-packet gain jitter, common to all chains
    double agcPerChainSigma_dB = 0.3;  //!< extra per chain
    double rssiSigma_dB = 1.0;
    bool awgn = true;  //!< receiver noise at the link budget's SNR
    /** Best SNR a real receiver's channel estimate reaches (EVM, phase noise, quantisation):
     *  combined with the link budget's as 1/SNR = 1/SNR_thermal + 1/SNR_cap. */
    double snrCap_dB = 35.0;
    std::optional<double> fixedSnr_dB;  //!< overrides the link budget's SNR when set
    double timingJitter = 0.3;          //!< frame time jitter, fraction of the frame period (< 1)
    /** Share of frames received a second time, as an 802.11 retry: the same sequence number,
     *  0.02–7 ms later, its own noise, sampling-time offset and CFO (real RT-AC86Us: 4.5 % of
     *  the muTrack D1 frames). */
    double retryProbability = 0.0;

    // 4366c0 inter-antenna jump states: each chain except 0 sits in one of `jumpStates`
    // delay states (0, step, 2·step, ...), switching at random (Poisson) times.
    bool antennaJumps = false;
    unsigned jumpStates = 3;
    double jumpStep_s = 3e-9;
    /** The states' delays, when not evenly stepped from 0 (`state_delays_ns`): e.g. the
     *  −20.9, −9.0, +4.1, +16.0 ns a real RT-AC86U chain shows at 20 MHz. Non-empty: its size is
     *  `jumpStates` and `jumpStep_s` is unused. */
    std::vector<double> jumpStateDelays_s;
    /** The delays are sample slips in the chain's digital front end (`baseband: true`): phase
     *  −2π·k·Δf·τ, the phase at the centre frequency unchanged, as the muTrack RT-AC86Us show
     *  (states' centre phases within 0.4°); false: a delay of the RF signal, −2π·f_k·τ. */
    bool jumpBaseband = false;
    double jumpRate_Hz = 0.2;
    /** Each state of each chain also has its own constant phase (uniform, fixed per boot), as
     *  real units report, on top of the phase its delay gives at the carrier. */
    bool jumpStatePhase = false;
    /** Until `jumpAllowedUntil_s` (drive time), chains take only these states (empty: all);
     *  e.g. a calibration drive that never visits a state the later drives see. */
    std::vector<unsigned> jumpAllowedStates;
    double jumpAllowedUntil_s = std::numeric_limits<double>::infinity();

    std::vector<unsigned> deadCores;      //!< receive chains that report nothing useful
    bool deadCoresMissing = false;        //!< true: pairs absent; false: present but all zero
    bool firmwareOverwrittenBins = true;  //!< PHY status words at k = 0,+1,+2 (28..30 @20 MHz)
    bool lowerSubbandSignFlip = true;     //!< 80 MHz: k = −128..−65 arrive negated (§4)

    /** No impairment at all: the CSI is the propagation channel, scaled, without noise. */
    static ImpairmentSpec ideal();
};

struct PropagationSpec
{
    unsigned maxReflectionOrder = 2;  //!< 0, 1 or 2 (image method)
    double minPathGain_dB = -40.0;    //!< paths weaker than this vs. the strongest are dropped
};

/** Everything the simulator needs, normally loaded from a YAML file (share/scenarios/README.md
 *  documents every key). */
struct Scenario
{
    std::string name;
    std::string description;
    std::string sourcePath;  //!< file it was read from ("" if from text)
    double duration_s = 60.0;
    uint32_t seed = 1;
    double startTime_unix = 1700000000.0;  //!< timestamp of t = 0

    std::vector<mrpt::math::TPoint2D> roomCorners;  //!< empty: open space (no room walls)
    std::vector<Wall> walls;                        //!< room edges first, then extra walls
    std::vector<Obstacle> obstacles;
    std::vector<Scatterer> scatterers;
    std::vector<TransmitterSpec> transmitters;
    ReceiverSpec receiver;
    MotionSpec motion;
    OdometrySpec odometry;
    ImpairmentSpec impairments;
    PropagationSpec propagation;

    /** Reads a scenario file; antenna array files are resolved relative to it.
     *  Throws ScenarioError naming file, line and key for unknown keys, bad values, a
     *  transmitter outside the room, an impossible channel... */
    static Scenario fromYamlFile(const std::string& path);

    /** As fromYamlFile() for a YAML text; `displayName` is used in messages and `baseDir` to
     *  resolve relative array paths. */
    static Scenario fromYamlText(
        const std::string& text, const std::string& displayName = "<text>",
        const std::string& baseDir = ".");

    /** Cross-checks a scenario built in code (the YAML reader runs it too): transmitters and
     *  motion inside the room, arrays large enough for the streams, unique names/MACs...
     *  Throws ScenarioError with the key path of the offending entry (line 0). */
    void validate() const;

    /** True if the point is inside the room polygon (always true in open space). */
    bool insideRoom(const mrpt::math::TPoint2D& p) const;

    /** Index of a transmitter by name or MAC text; throws std::out_of_range if none. */
    size_t transmitterIndex(const std::string& nameOrMac) const;
};

}  // namespace mrpt_wifi::sim
