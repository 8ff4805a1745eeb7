/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/obs/MacAddress.h>

#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace mrpt_wifi
{
/** A calibration that does not fit the CSI or array it is applied to (wrong channel, device,
 *  antenna count), or a malformed calibration file. The message says what and where. */
class CalibrationError : public std::runtime_error
{
public:
    using std::runtime_error::runtime_error;
};

/** Phase (and optional gain) calibration of one receiver, for one (device, channel, bandwidth).
 *
 * Applying it: the CSI of antenna i at subcarrier k is multiplied by
 * e^{−j·phases_rad[i][k]} · 10^{−gains_db[i]/20}, *after* the 80 MHz sub-band sign correction
 * (CsiPreprocessing) and before the sampling-time-offset removal. A phase common to all antennas
 * at one subcarrier does not change bearings; calibration tools usually fix antenna 0 to zero.
 *
 * File format (YAML, one file per device × channel × bandwidth; angles in radians):
 * \code
 * format: mrpt_wifi_phase_calibration
 * version: 1
 * device: rt-ac86u            # must equal the `name` of the receiver's array file
 * chanspec: 155/80            # centre channel / bandwidth [MHz] (the sideband does not matter)
 * date: 2024-05-02T10:31:00Z  # when it was made (free text, ISO 8601 recommended)
 * frames_used: 1832
 * residual_rad: 0.061         # RMS phase residual of the fit
 * method: wifi-calibrate drive (PCA + LM)
 * subband_sign_corrected: true  # phases are relative to sign-corrected CSI (must be true)
 * antennas: 4
 * subcarriers: [-122, -121, ...]   # k, ascending; every data subcarrier should be listed
 * phases_rad:                  # [antenna][subcarrier], one row per antenna
 *   - [0.0, 0.0, ...]
 *   - [1.234, 1.229, ...]
 * gains_db: [0.0, 0.4, -0.2, 0.1]  # optional, per antenna
 * \endcode
 *
 *
 * Version 2 adds the transmit side: `role: transmitter` (default `receiver`), `transmitter:
 * aa:bb:cc:dd:ee:ff` (the access point, required for that role) and `aod_residual_rad` (RMS
 * AoD error left on the calibration drive, added to every AoD σ). For a transmitter the rows
 * are its transmit chains (stream m leaves from chain m), `device` is the name of its array
 * file, and the CSI of stream m is multiplied by e^{−j·phases_rad[m][k]} · 10^{−gains_db[m]/20}
 * after the per-stream sampling-time-offset removal (CsiPreprocessing). Version 1 files load as
 * receiver calibrations.
 *
 * Version 3 adds the receive chains' jump states (the BCM4366c0's inter-chain delay jumps,
 * ChainStates.h): for each antenna i ≥ 1 and each state s a drive visited, `delay_ns` (the
 * measured delay of antenna i relative to antenna 0 in that state: what a frame is classified
 * by), `delta_delay_ns` and `delta_phase_rad` (the state relative to the antenna's reference
 * state, in which `phases_rad` holds) and `frames`. The CSI of antenna i in state s is first
 * multiplied by e^{+j·2π·k·312.5 kHz·delta_delay}·e^{−j·delta_phase}, then as above:
 * \code
 * chain_state_tolerance_ns: 1.0   # a frame's delay within this of a state's is that state
 * chain_states:
 *   - antenna: 1
 *     state: 0
 *     delay_ns: 0.21
 *     delta_delay_ns: 0
 *     delta_phase_rad: 0
 *     frames: 2210
 *   - antenna: 1
 *     state: 1
 *     ...
 * \endcode
 * A file without `chain_states` is state-unaware: it holds in whatever state the chains were
 * in when it was made.
 *
 * Folder layout, loaded by channel (CalibrationStore): `DIR/<device>/ch<centre>_<bw>mhz.yaml`,
 * e.g. `calib/rt-ac86u/ch155_80mhz.yaml`, `calib/rt-ac86u/ch36_80mhz.yaml`; transmitters in
 * `DIR/transmitters/<mac with dashes>/ch<centre>_<bw>mhz.yaml`. */
/** One jump state of one receive chain, as a calibration holds it (see PhaseCalibration). */
struct ChainStateCalibration
{
    unsigned antenna = 1;
    uint8_t state = 0;
    double delay_s = 0;         //!< measured delay relative to antenna 0 in this state
    double deltaDelay_s = 0;    //!< relative to the antenna's reference state
    double deltaPhase_rad = 0;  //!< relative to the antenna's reference state
    uint64_t frames = 0;        //!< frames of the calibration drive in this state
};

struct PhaseCalibration
{
    static constexpr int kFormatVersion = 3;
    enum class Role : uint8_t
    {
        Receiver,    //!< the robot's receive array (rows: receive chains)
        Transmitter  //!< one access point's transmit chains (rows: transmit chains)
    };

    std::string device;
    Chanspec chanspec;
    std::string date;
    uint64_t framesUsed = 0;
    double residual_rad = 0;
    std::string method;
    bool subbandSignCorrected = true;
    std::vector<int> subcarriers;                 //!< k, ascending
    std::vector<std::vector<double>> phases_rad;  //!< [antenna][index into subcarriers]
    std::vector<double> gains_dB;                 //!< empty or one per antenna
    std::string sourcePath;                       //!< file it was read from
    Role role = Role::Receiver;
    MacAddress transmitter;      //!< Role::Transmitter: the access point
    double aodResidual_rad = 0;  //!< Role::Transmitter: RMS AoD error after calibration
    /** Receiver: the jump states the calibration knows (empty: state-unaware). */
    std::vector<ChainStateCalibration> chainStates;
    double chainStateTolerance_s = 1.0e-9;
    /** Receiver: the calibration recording showed jump states that differ by a delay alone (a
     *  sample slip, as on real RT-AC86Us), so they are not listed: the phases hold in every
     *  state (`chain_states_delay_only: true`, version 3). */
    bool chainStatesDelayOnly = false;

    /** The state entry of (antenna, state), or nullptr. */
    const ChainStateCalibration* findChainState(unsigned antenna, uint8_t state) const;
    /** The state of `antenna` whose delay is nearest to `delay_s` within the tolerance, or
     *  nullptr. */
    const ChainStateCalibration* matchChainState(unsigned antenna, double delay_s) const;

    size_t antennas() const { return phases_rad.size(); }

    /** Reads a calibration file; throws CalibrationError naming the file and the problem. */
    static PhaseCalibration fromYamlFile(const std::string& path);
    static PhaseCalibration fromYamlText(
        const std::string& text, const std::string& displayName = "<text>");
    std::string asYamlText() const;
    /** Writes the file (creating parent folders); throws CalibrationError on failure. */
    void saveYamlFile(const std::string& path) const;

    /** Consistency (sizes, ascending subcarriers, finite values); throws CalibrationError. */
    void validate(const std::string& where = "calibration") const;

    /** Phase [rad] of antenna i at subcarrier k: the listed value, linearly interpolated between
     *  listed neighbours (unwrapped), held constant beyond the ends. */
    double phaseAt(size_t antenna, int k) const;
    /** Gain [dB] of antenna i (0 if the file has none). */
    double gainAt(size_t antenna) const { return gains_dB.empty() ? 0.0 : gains_dB.at(antenna); }

    /** Same centre channel and bandwidth. */
    bool matchesChannel(const Chanspec& cs) const;
    /** Throws CalibrationError with a clear message unless this calibration is for `device`,
     *  the channel of `cs` and at least `nRx` antennas. */
    void checkCompatible(const std::string& deviceName, const Chanspec& cs, size_t nRx) const;

    /** `ch155_80mhz.yaml` */
    static std::string fileNameFor(const Chanspec& cs);
    /** `DIR/<device>/ch155_80mhz.yaml` */
    static std::string pathFor(
        const std::string& dir, const std::string& device, const Chanspec& cs);
    /** `DIR/transmitters/02-00-00-00-01-01/ch155_80mhz.yaml` */
    static std::string transmitterPathFor(
        const std::string& dir, const MacAddress& mac, const Chanspec& cs);
};

/** Where calibrations come from: one file (for one channel) or a folder with the layout above.
 *  Files are loaded on first use and cached. */
class CalibrationStore
{
public:
    CalibrationStore() = default;
    /** A file or a folder; throws CalibrationError if the path does not exist or a file is
     *  malformed. */
    static CalibrationStore open(const std::string& fileOrDir);
    static CalibrationStore fromCalibration(PhaseCalibration c);

    bool empty() const { return !single_ && dir_.empty(); }
    bool isFolder() const { return !dir_.empty(); }
    const std::string& path() const { return path_; }

    /** The calibration for (device, channel), or nullptr if there is none for that channel.
     *  Throws CalibrationError if the one found is for another device, or does not fit nRx. */
    const PhaseCalibration* find(const std::string& device, const Chanspec& cs, size_t nRx) const;

    /** The transmit-chain calibration of one access point on a channel (folders only), or
     *  nullptr. Throws CalibrationError if the file is malformed, for another transmitter or
     *  channel, or has fewer chains than `streams`. */
    const PhaseCalibration* findTransmitter(
        const MacAddress& mac, const Chanspec& cs, size_t streams) const;

    /** What the folder holds for a device (file names), for messages. */
    std::vector<std::string> available(const std::string& device) const;
    /** For a channel find() has nothing for: which channel, what the store holds, and the
     *  wifi-calibrate run that writes the missing file (a drive among known access points with
     *  frames on that channel). */
    std::string missingChannelAdvice(const std::string& device, const Chanspec& cs) const;

private:
    std::string path_, dir_;
    std::shared_ptr<PhaseCalibration> single_;
    mutable std::map<std::string, std::shared_ptr<PhaseCalibration>> cache_;
};

}  // namespace mrpt_wifi
