/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-calibrate: phase calibration of the receive array from a rawlog recorded while the robot
 * drove near a transmitter at a known position (or through a splitter), one YAML file per
 * channel in the folder layout the estimators and the sensor load; --check tells whether an
 * existing calibration still fits (e.g. after a router reboot). A splitter calibration may come
 * from several captures, each feeding some of the chains (SplitterCalibration.h). */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt_wifi/calib/CalibrationCheck.h>
#include <mrpt_wifi/calib/CalibrationInput.h>
#include <mrpt_wifi/calib/CalibrationReport.h>
#include <mrpt_wifi/calib/PhaseCalibrator.h>
#include <mrpt_wifi/calib/SplitterCalibration.h>
#include <mrpt_wifi/obs/CommandLine.h>

#include <cmath>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

using namespace mrpt_wifi;
using namespace mrpt_wifi::calib;

namespace
{
constexpr double kDeg = 180.0 / M_PI;

std::vector<double> numbers(const std::string& text, size_t count, const std::string& what)
{
    std::istringstream is(text);
    std::vector<double> v;
    double x;
    while (is >> x) v.push_back(x);
    if (v.size() != count || !is.eof())
        throw std::invalid_argument(
            what + ": expected " + std::to_string(count) + " numbers, got '" + text + "'");
    return v;
}

std::string listMacs(const RawlogSummary& s)
{
    std::ostringstream o;
    for (const auto& [mac, src] : s.transmitters)
        o << "\n  " << mac.asString() << "  " << src.frames << " frames";
    return o.str();
}

std::string fixed(double v, int p = 1)
{
    std::ostringstream o;
    o << std::fixed << std::setprecision(p) << v;
    return o.str();
}

std::string signedFixed(double v, int p)
{
    return (v >= 0 ? "+" : "") + fixed(v, p);
}

/** Circular mean [rad] of a phase curve. */
double meanPhase(const std::vector<double>& p)
{
    std::complex<double> s = 0;
    for (double v : p) s += std::polar(1.0, v);
    return std::arg(s);
}

/** Refuses a transmitter's frames when the array can't read their receive cores (saying what
 *  to change); warns when the frames have fewer chains than an array without `cores`. */
void checkFrameShape(
    const AntennaArray& array, const std::string& arrayArg, const MacAddress& mac,
    const RawlogSummary::Source& src)
{
    CsiPreprocessor pre(calibrationPreprocessOptions(), array);
    CObservationWiFiCSI shape;
    shape.nRx = uint8_t(src.maxRx);
    shape.rxCores = src.rxCores;
    const std::string why = pre.coreMismatchMessage(shape);
    if (!why.empty())
        throw std::runtime_error("frames from " + mac.asString() + " (" + arrayArg + "): " + why);
    if (array.cores.empty() && src.maxRx < array.size())
        std::cerr << "wifi-calibrate: warning: frames from " << mac.asString() << " have "
                  << src.maxRx << " receive chains, the array " << array.size()
                  << " elements: using the first " << src.maxRx << "\n";
}

/** Receive cores "0,1" (or "0 1") of --fed-cores as array elements, ascending. */
std::vector<unsigned> fedElements(const std::string& text, const AntennaArray& array)
{
    std::string t = text;
    std::replace(t.begin(), t.end(), ',', ' ');
    std::istringstream is(t);
    std::set<unsigned> elements;
    std::string word;
    while (is >> word)
    {
        size_t used = 0;
        int core = -1;
        try
        {
            core = std::stoi(word, &used);
        }
        catch (const std::exception&)
        {
        }
        if (core < 0 || used != word.size())
            throw std::invalid_argument(
                "--fed-cores '" + text + "': '" + word + "' is not a receive core number");
        bool found = false;
        for (unsigned e = 0; e < array.size(); ++e)
            if (array.coreOf(e) == unsigned(core)) elements.insert(e), found = true;
        if (!found)
            throw std::invalid_argument(
                "--fed-cores '" + text + "': the array '" + array.name + "' reads no core " + word);
    }
    return {elements.begin(), elements.end()};
}

/** What wifi-calibrate --static-splitter needs besides the inputs. */
struct SplitterRun
{
    AntennaArray array;
    std::string arrayArg, outDir, reportDir;
    std::optional<MacAddress> onlyMac;
    std::optional<Chanspec> onlyChannel;
    PreprocessOptions pre;
    CalibratorOptions calibrator;
    std::vector<std::string> fedCores;  //!< per input; empty: detect
    double maxDisagreement_rad = 0;
    ChainStatePolicy chainStates = ChainStatePolicy::Auto;
    bool force = false, quiet = false;
};

std::string coreList(const AntennaArray& a, const std::vector<unsigned>& elements)
{
    std::string s;
    for (size_t i = 0; i < elements.size(); ++i)
        s += (i ? ", " : "") + std::to_string(a.coreOf(elements[i]));
    return s;
}

/** Static splitter calibration from one or more captures, each feeding element 0 and some
 *  of the others; one calibration file per channel for every element. */
int calibrateSplitter(const std::vector<std::string>& inputs, const SplitterRun& run)
{
    const AntennaArray& array = run.array;
    std::map<uint32_t, std::vector<SplitterCapture>> byChannel;
    bool allDetermined = true;
    std::cout << "Array      : " << array.name << " (" << array.size() << " elements, "
              << run.arrayArg << ")\n"
              << "Mode       : static splitter, " << inputs.size() << " capture(s)\n";
    for (size_t c = 0; c < inputs.size(); ++c)
    {
        const std::string& in = inputs[c];
        cli::Progress p1("wifi-calibrate: scanning " + in, !run.quiet);
        const RawlogSummary summary = summarizeRawlog(in, [&](double f) { p1.update(f); });
        p1.done(std::to_string(summary.csiFrames) + " CSI frames");
        if (summary.csiFrames == 0)
            throw std::runtime_error("'" + in + "' holds no CObservationWiFiCSI observations");
        MacAddress mac;
        if (run.onlyMac)
        {
            if (!summary.transmitters.count(*run.onlyMac))
                throw std::runtime_error(
                    "transmitter " + run.onlyMac->asString() + " never appears in '" + in +
                    "'; it holds frames from:" + listMacs(summary));
            mac = *run.onlyMac;
        }
        else if (summary.transmitters.size() == 1)
            mac = summary.transmitters.begin()->first;
        else
            throw std::runtime_error(
                "'" + in + "' holds frames from " + std::to_string(summary.transmitters.size()) +
                " transmitters: choose the splitter's with --mac" + listMacs(summary));
        checkFrameShape(array, run.arrayArg, mac, summary.transmitters.at(mac));

        // Each pass reads the capture with a fresh preparer: the same frames, the same states.
        const auto forEachFrame = [&](const std::string& what, auto&& onFrame)
        {
            FramePreparer preparer(array, run.pre);
            CalibrationFrame frame;
            std::map<std::string, uint64_t> rejected;
            uint64_t accepted = 0;
            cli::Progress p("wifi-calibrate: " + what, !run.quiet);
            readRawlog(
                in,
                [&](const CObservationWiFiCSI& obs)
                {
                    if (obs.transmitter != mac) return;
                    if (run.onlyChannel &&
                        (obs.chanspec.centerChannel != run.onlyChannel->centerChannel ||
                         obs.chanspec.bandwidthMHz != run.onlyChannel->bandwidthMHz))
                        return;
                    const RejectReason r = preparer.prepareStatic(obs, frame);
                    if (r != RejectReason::Accepted)
                    {
                        ++rejected[toString(r)];
                        return;
                    }
                    ++accepted;
                    onFrame(frame);
                },
                {}, [&](double f) { p.update(f); });
            p.done(std::to_string(accepted) + " frames");
            if (accepted == 0)
            {
                std::string why;
                for (const auto& [r, n] : rejected) why += ", " + std::to_string(n) + " " + r;
                throw std::runtime_error(
                    "'" + in + "': no usable frame from " + mac.asString() +
                    (run.onlyChannel ? " on " + run.onlyChannel->asString() : std::string()) +
                    (why.empty() ? std::string() : " (" + why.substr(2) + ")"));
            }
            return accepted;
        };

        // Which elements the splitter feeds: given, or told by how flat each one's CSI is
        // against element 0's.
        SplitterFeedDetector detector;
        const uint64_t frames = forEachFrame(
            "detecting fed chains", [&](const CalibrationFrame& f) { detector.add(f); });
        const SplitterFeedDetector::Verdict verdict = detector.decide();
        std::ostringstream flat;
        for (unsigned e = 1; e < verdict.flatness.size(); ++e)
            flat << (e > 1 ? ", " : "") << "core " << array.coreOf(e) << " "
                 << fixed(verdict.flatness[e], 3);
        std::vector<unsigned> fed;
        if (!run.fedCores.empty())
            fed = fedElements(run.fedCores[c], array);
        else
        {
            if (verdict.fed.empty())
                throw SplitterError(
                    "'" + in + "': no chain is fed together with core " +
                    std::to_string(array.coreOf(0)) +
                    " (element 0): none has a flat phase against it (median RMS across the "
                    "subcarriers: " +
                    flat.str() + " rad; a fed chain stays below " +
                    fixed(SplitterFeedDetector::kMaxFedFlatness, 2) +
                    "). Is the splitter connected to core " + std::to_string(array.coreOf(0)) +
                    "? Name the fed cores with --fed-cores if it is");
            if (!verdict.undecided.empty())
                throw SplitterError(
                    "'" + in + "': cannot tell whether " +
                    describeElement(array, verdict.undecided.front()) +
                    " is fed by the splitter (median phase RMS across the subcarriers against "
                    "core " +
                    std::to_string(array.coreOf(0)) + ": " + flat.str() +
                    " rad); name the fed cores with --fed-cores, one per capture");
            fed = verdict.fed;
        }
        if (fed.empty() || fed.front() != 0 || fed.size() < 2)
            throw SplitterError(
                "'" + in + "': the fed cores (" + coreList(array, fed) + ") must include core " +
                std::to_string(array.coreOf(0)) +
                " (element 0, the reference every capture shares) and at least one other");
        std::cout << "\nCapture    : " << in << " (" << summary.csiFrames << " CSI frames, "
                  << frames << " used, transmitter " << mac.asString() << ")\n"
                  << "  fed chains       : cores " << coreList(array, fed)
                  << (run.fedCores.empty() ? " (detected" : " (--fed-cores") << "; phase RMS "
                  << "across subcarriers against core " << array.coreOf(0) << ": " << flat.str()
                  << " rad)\n";

        PhaseCalibrator calibrator(subArray(array, fed), run.calibrator);
        CalibrationFrame restricted;
        forEachFrame(
            "reading",
            [&](const CalibrationFrame& f)
            {
                restrictFrame(f, fed, restricted);
                calibrator.add(restricted);
            });
        if (calibrator.channels().empty())
            throw std::runtime_error(
                "'" + in +
                "': no frame could be grouped by the chains' jump states (a fed "
                "chain's state never measurable): nothing to calibrate");
        for (const Chanspec& cs : calibrator.channels())
        {
            SplitterCapture cap;
            cap.name = in;
            cap.elements = fed;
            cap.result = calibrator.solve(cs);
            const auto& d = cap.result.diag;
            const auto& cal = cap.result.calibration;
            std::cout << "  " << cs.asString() << "          : " << d.frames << " frames over "
                      << fixed(d.duration_s) << " s, common signal in "
                      << fixed(100 * d.losShare, 0) << " %, phase residual "
                      << fixed(d.residual_rad * kDeg, 2) << " deg RMS\n"
                      << "  offsets          :";
            for (size_t r = 1; r < cal.antennas(); ++r)
                std::cout << " core " << array.coreOf(fed[r]) << " "
                          << fixed(meanPhase(cal.phases_rad[r]) * kDeg, 1) << " deg";
            std::cout << " (mean over subcarriers, against core " << array.coreOf(0) << ")\n";
            for (const auto& st : d.chainStates)
                std::cout << "    core " << array.coreOf(fed[st.antenna]) << " state "
                          << int(st.state) << ": " << std::setw(6) << st.frames << " frames, delay "
                          << signedFixed(st.delay_s * 1e9, 2) << " ns"
                          << (st.reference
                                  ? " (reference)"
                                  : ", offset " + signedFixed(st.deltaDelay_s * 1e9, 2) + " ns " +
                                        signedFixed(st.deltaPhase_rad * kDeg, 1) + " deg")
                          << "\n";
            if (d.chainStateChanges > 0)
                std::cout << "    " << d.chainStateChanges << " state changes, "
                          << d.unknownStateFrames << " frames left out\n";
            for (const auto& w : cap.result.warnings)
                std::cerr << "wifi-calibrate: warning: " << in << " " << cs.asString() << ": " << w
                          << "\n";
            allDetermined = allDetermined && cap.result.determined();
            if (!run.reportDir.empty())
                for (const auto& png : writeCalibrationReport(
                         cap.result, run.reportDir + "/" + std::to_string(c + 1)))
                    std::cout << "  report           : " << png << "\n";
            byChannel[(uint32_t(cs.centerChannel) << 16) | cs.bandwidthMHz].push_back(
                std::move(cap));
        }
    }

    int rc = 0;
    for (const auto& [key, captures] : byChannel)
    {
        std::vector<SplitterMergeNote> notes;
        PhaseCalibration merged =
            mergeSplitterCaptures(captures, array, run.maxDisagreement_rad, &notes);
        std::cout << "\nChannel " << merged.chanspec.asString() << " (" << merged.antennas()
                  << " elements, " << merged.subcarriers.size() << " subcarriers, "
                  << captures.size() << " capture(s))\n";
        for (const auto& n : notes)
        {
            std::cout << "  " << describeElement(array, n.element) << ": "
                      << fixed(meanPhase(merged.phases_rad[n.element]) * kDeg, 1) << " deg from "
                      << n.from;
            for (const auto& a : n.agreeing) std::cout << ", agreeing with " << a;
            if (!n.agreeing.empty())
                std::cout << " (within " << fixed(n.maxDisagreement_rad * kDeg, 1) << " deg)";
            std::cout << "\n";
        }
        const std::string path = PhaseCalibration::pathFor(run.outDir, array.name, merged.chanspec);
        const size_t states = merged.chainStates.size();
        const std::string policy = applyChainStatePolicy(merged, run.chainStates);
        std::cout << "  chain states     : "
                  << (policy.empty() ? std::to_string(states) + " jump states in the file" : policy)
                  << "\n";
        if (allDetermined || run.force)
        {
            merged.saveYamlFile(path);
            std::cout << "  written          : " << path
                      << (allDetermined ? "" : " (forced despite the warnings)") << "\n";
        }
        else
        {
            std::cout << "  NOT written      : " << path
                      << " (a capture cannot determine its chains, see the warnings; --force "
                         "writes it anyway)\n";
            rc = 2;
        }
    }
    return rc;
}
}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "wifi-calibrate",
        [&]() -> int
        {
            TCLAP::CmdLine cmd(
                "Phase calibration of a WiFi CSI receive array (per antenna and subcarrier) from "
                "a rawlog recorded while the robot drove within a few metres of a transmitter at "
                "a known position: expected bearings from the robot poses, suppression, "
                "principal component, Levenberg-Marquardt refinement; or, with "
                "--static-splitter, from one or more captures through a splitter, each feeding "
                "core 0 and some of the others (the fed chains detected or given with "
                "--fed-cores), merged into one file. Writes one YAML file per "
                "channel as OUT/<device>/ch<centre>_<bw>mhz.yaml. Exit codes: 0 written/OK, "
                "1 error (also: no usable frame, a chain no capture feeds, captures that "
                "disagree), 2 a drive that cannot determine the calibration (nothing written, "
                "see --force), 3 --check found the calibration stale.",
                ' ', "0.1");
            TCLAP::UnlabeledMultiArg<std::string> argIn(
                "input",
                "Rawlog with CObservationWiFiCSI (and odometry); with --static-splitter one or "
                "more, one per splitter wiring",
                true, "IN.rawlog", cmd);
            TCLAP::ValueArg<std::string> argArray(
                "a", "array", "Receive array: a geometry file, or a shipped one by name (rt-ac86u)",
                true, "", "ARRAY.yaml", cmd);
            TCLAP::ValueArg<std::string> argTx(
                "", "tx-position", "Transmitter position x y [m], in the frame of the poses", false,
                "", "x y", cmd);
            TCLAP::ValueArg<std::string> argTxFile(
                "", "transmitters",
                "YAML list of transmitters (mac, position) - e.g. wifi-sim's transmitters.yaml",
                false, "", "FILE.yaml", cmd);
            TCLAP::ValueArg<std::string> argMac(
                "", "mac", "Use only frames from this transmitter", false, "", "MAC", cmd);
            TCLAP::ValueArg<std::string> argPoses(
                "", "poses",
                "Robot poses: 'odometry' (CObservationOdometry in the rawlog) or a TUM "
                "trajectory file (t x y z qx qy qz qw)",
                false, "odometry", "odometry|FILE", cmd);
            TCLAP::ValueArg<std::string> argOrigin(
                "", "odom-origin",
                "Where the odometry reads 0 0 0, in the frame of --tx-position / --transmitters "
                "(the map's): x y yaw (m, m, deg)",
                false, "0 0 0", "x y yaw", cmd);
            TCLAP::ValueArg<std::string> argChannel(
                "c", "channel", "Only this channel (155/80, or Broadcom notation 149/80)", false,
                "", "CH/BW", cmd);
            TCLAP::ValueArg<double> argMinRssi(
                "", "min-rssi", "Ignore frames weaker than this [dBm]", false, -127, "dBm", cmd);
            TCLAP::ValueArg<std::string> argOut(
                "o", "out", "Calibration folder (DIR/<device>/ch<c>_<bw>mhz.yaml)", false, "",
                "DIR", cmd);
            TCLAP::ValueArg<std::string> argReport(
                "", "report", "Write report pictures (PNG) into this folder", false, "", "DIR",
                cmd);
            TCLAP::SwitchArg argForce(
                "f", "force", "Write the calibration even if the drive cannot determine it", cmd);
            TCLAP::SwitchArg argSplitter(
                "", "static-splitter",
                "Static calibration: one transmitter through a splitter and equal cables (no "
                "poses, no transmitter position). Several inputs: one capture per wiring, each "
                "feeding the array's element 0 (its first core) and some others (e.g. cores 0+1, "
                "then 0+3); the chains each capture feeds are detected (a fed chain's phase "
                "against element 0 is flat across the subcarriers, an unfed one hears the "
                "transmitter through its own multipath) or given with --fed-cores; every "
                "element must be fed by some capture. One file for all elements",
                cmd);
            TCLAP::MultiArg<std::string> argFed(
                "", "fed-cores",
                "With --static-splitter: the receive cores the splitter feeds in one capture "
                "(e.g. 0,1), once per input in the inputs' order; instead of detecting them",
                false, "C,C,..", cmd);
            TCLAP::ValueArg<double> argDisagree(
                "", "max-disagreement",
                "With --static-splitter: captures feeding the same chain must agree on its "
                "offset within this, in a jump state both saw [deg]",
                false, 5.0, "DEG", cmd);
            TCLAP::ValueArg<std::string> argCheck(
                "", "check",
                "Do not calibrate: check whether this calibration (file or folder) still fits "
                "the rawlog (stale after a reboot?)",
                false, "", "CALIB", cmd);
            TCLAP::ValueArg<double> argSegment(
                "", "segment", "Seconds of frames per robust-loss segment", false, 0.5, "S", cmd);
            TCLAP::ValueArg<double> argRobust(
                "", "robust-scale", "Cauchy scale of the robust loss (0: least squares)", false,
                0.3, "X", cmd);
            TCLAP::SwitchArg argTxChains(
                "", "transmit-chains",
                "Also calibrate the transmit chains of every multi-antenna transmitter listed in "
                "--transmitters (needs its yaw_deg and array/array_elements): the receiver's "
                "method mirrored at the AP, from the same drive. Written as "
                "OUT/transmitters/<mac>/ch<c>_<bw>mhz.yaml; csi-bearings --calib OUT then reports "
                "AoD for those transmitters",
                cmd);
            TCLAP::ValueArg<std::string> argChainStates(
                "", "chain-states",
                "Jump states in the file: auto (unless every state differs from its reference "
                "by a delay alone, a sample slip whose offsets hold in every state: over the air "
                "such states can't be matched to the file's and would withhold bearings), on, "
                "off",
                false, "auto", "auto|on|off", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress display", cmd);

            cli::JoinedArgv a1(argc, argv, "--tx-position", 2);
            cli::JoinedArgv a2(a1.argc(), const_cast<char**>(a1.argv()), "--odom-origin", 3);
            if (const int rc = cli::parseCommandLine(cmd, a2.argc(), a2.argv()); rc >= 0) return rc;

            // ---- Arguments that need no data ------------------------------------------------
            const bool splitter = argSplitter.isSet();
            const bool checking = argCheck.isSet();
            const std::vector<std::string> inputs = argIn.getValue();
            if (inputs.size() > 1 && !splitter)
                throw std::invalid_argument(
                    "several inputs are for --static-splitter (one capture per splitter "
                    "wiring); a drive is one rawlog");
            if (argFed.isSet() && !splitter)
                throw std::invalid_argument("--fed-cores is for --static-splitter");
            if (argFed.isSet() && argFed.getValue().size() != inputs.size())
                throw std::invalid_argument(
                    "--fed-cores given " + std::to_string(argFed.getValue().size()) +
                    " times for " + std::to_string(inputs.size()) +
                    " inputs: give it once per input, in the same order");
            if (splitter && checking)
                throw std::invalid_argument("--check needs a drive (not --static-splitter)");
            const ChainStatePolicy chainStatePolicy =
                chainStatePolicyFromString(argChainStates.getValue(), "--chain-states");
            if (!(argDisagree.getValue() > 0 && argDisagree.getValue() < 180))
                throw std::invalid_argument("--max-disagreement must be in (0, 180) degrees");
            if (!checking && !argOut.isSet())
                throw std::invalid_argument("--out DIR is required (or --check CALIB)");
            if (!splitter && argTx.isSet() == argTxFile.isSet())
                throw std::invalid_argument(
                    "give the transmitter position with exactly one of --tx-position x y or "
                    "--transmitters FILE (or use --static-splitter)");
            const AntennaArray array = AntennaArray::fromFileOrName(argArray.getValue(), "--array");
            if (array.size() < 2)
                throw std::invalid_argument(
                    "the array '" + array.name + "' has one element: nothing to calibrate");
            std::vector<TransmitterSite> sites;
            if (argTx.isSet())
            {
                const auto v = numbers(argTx.getValue(), 2, "--tx-position");
                sites.push_back({"tx", std::nullopt, {v[0], v[1]}, std::nullopt, std::nullopt});
            }
            else if (argTxFile.isSet())
                sites = loadTransmitterSites(argTxFile.getValue());
            const bool txChains = argTxChains.getValue();
            if (txChains && (splitter || !argTxFile.isSet() || checking))
                throw std::invalid_argument(
                    "--transmit-chains needs a drive with --transmitters FILE (each entry with "
                    "position, yaw_deg and array), not --static-splitter or --check");
            if (txChains)
                for (const auto& s : sites)
                    if (!s.yaw_rad || !s.array)
                        throw std::invalid_argument(
                            argTxFile.getValue() + ": transmitter '" + s.name +
                            "' needs yaw_deg and array (or array_elements) for --transmit-chains");
            std::optional<MacAddress> onlyMac;
            if (argMac.isSet()) onlyMac = MacAddress::fromString(argMac.getValue());
            std::optional<Chanspec> onlyChannel;
            if (argChannel.isSet()) onlyChannel = Chanspec::fromString(argChannel.getValue());
            const auto origin = numbers(argOrigin.getValue(), 3, "--odom-origin");
            std::optional<CalibrationStore> checkStore;
            if (checking) checkStore = CalibrationStore::open(argCheck.getValue());

            if (splitter)
            {
                SplitterRun run;
                run.array = array;
                run.arrayArg = argArray.getValue();
                run.outDir = argOut.getValue();
                run.reportDir = argReport.getValue();
                run.onlyMac = onlyMac;
                run.onlyChannel = onlyChannel;
                run.pre = calibrationPreprocessOptions();
                run.pre.minRssi_dBm = argMinRssi.getValue();
                run.calibrator.mode = CalibrationMode::Splitter;
                run.calibrator.segment_s = argSegment.getValue();
                run.calibrator.robustScale = argRobust.getValue();
                run.fedCores = argFed.getValue();
                run.maxDisagreement_rad = argDisagree.getValue() / kDeg;
                run.force = argForce.getValue();
                run.chainStates = chainStatePolicy;
                run.quiet = argQuiet.getValue();
                return calibrateSplitter(inputs, run);
            }
            const std::string input = inputs.front();

            // ---- First pass: is the input usable? ------------------------------------------
            cli::Progress p1("wifi-calibrate: scanning", !argQuiet.getValue());
            const RawlogSummary summary = summarizeRawlog(input, [&](double f) { p1.update(f); });
            p1.done(std::to_string(summary.csiFrames) + " CSI frames");
            if (summary.csiFrames == 0)
                throw std::runtime_error(
                    "'" + input + "' holds no CObservationWiFiCSI observations");

            // Which transmitters' frames to use, and where each one is.
            std::map<MacAddress, mrpt::math::TPoint2D> txAt;
            std::map<MacAddress, const TransmitterSite*> siteOf;
            std::set<MacAddress> use;
            if (onlyMac && !summary.transmitters.count(*onlyMac))
                throw std::runtime_error(
                    "transmitter " + onlyMac->asString() + " never appears in '" + input +
                    "'; it holds frames from:" + listMacs(summary));
            if (splitter || argTx.isSet())
            {
                if (onlyMac)
                    use.insert(*onlyMac);
                else if (summary.transmitters.size() == 1)
                    use.insert(summary.transmitters.begin()->first);
                else
                    throw std::runtime_error(
                        "the rawlog holds frames from " +
                        std::to_string(summary.transmitters.size()) +
                        " transmitters: choose one with --mac" + listMacs(summary));
                if (!sites.empty()) txAt[*use.begin()] = sites.front().position;
            }
            else
            {
                for (const auto& s : sites)
                {
                    if (!s.mac)
                        throw std::runtime_error(
                            argTxFile.getValue() + ": transmitter '" + s.name + "' has no mac");
                    if (onlyMac && *s.mac != *onlyMac) continue;
                    txAt[*s.mac] = s.position;
                    siteOf[*s.mac] = &s;
                    if (summary.transmitters.count(*s.mac)) use.insert(*s.mac);
                }
                if (onlyMac && !txAt.count(*onlyMac))
                    throw std::runtime_error(
                        "transmitter " + onlyMac->asString() + " is not listed in " +
                        argTxFile.getValue());
                if (use.empty())
                    throw std::runtime_error(
                        "none of the transmitters in " + argTxFile.getValue() +
                        " appears in the rawlog; it holds frames from:" + listMacs(summary));
            }

            // Antennas and channels of the chosen frames.
            std::map<std::string, uint64_t> channels;
            for (const auto& mac : use)
            {
                const auto& src = summary.transmitters.at(mac);
                checkFrameShape(array, argArray.getValue(), mac, src);
                for (const auto& [cs, n] : src.channels) channels[cs] += n;
            }
            if (onlyChannel)
            {
                bool found = false;
                for (const auto& [cs, n] : channels)
                    found |= Chanspec::fromString(cs).centerChannel == onlyChannel->centerChannel &&
                             Chanspec::fromString(cs).bandwidthMHz == onlyChannel->bandwidthMHz;
                if (!found)
                {
                    std::string have;
                    for (const auto& [cs, n] : channels) have += " " + cs;
                    throw std::runtime_error(
                        "no frames on channel " + onlyChannel->asString() +
                        " from the chosen transmitter(s); channels present:" + have);
                }
            }

            // Robot poses.
            PoseTrack poses;
            if (!splitter)
            {
                if (argPoses.getValue() == "odometry")
                {
                    if (summary.odometryReadings == 0)
                        throw std::runtime_error(
                            "the rawlog has no robot poses (no CObservationOdometry): record "
                            "odometry with the CSI, or give a TUM trajectory with --poses FILE");
                    poses = summary.odometry;
                }
                else
                    poses = PoseTrack::fromTumFile(argPoses.getValue());
                poses =
                    poses.transformed(mrpt::math::TPose2D(origin[0], origin[1], origin[2] / kDeg));
                if (poses.endTime() < summary.firstCsiTime ||
                    poses.startTime() > summary.lastCsiTime)
                    throw std::runtime_error(
                        "the poses (" + fixed(poses.startTime(), 2) + " .. " +
                        fixed(poses.endTime(), 2) + " s) do not overlap the CSI frames (" +
                        fixed(summary.firstCsiTime, 2) + " .. " + fixed(summary.lastCsiTime, 2) +
                        " s)");
            }

            // ---- Second pass: the frames -------------------------------------------------
            PreprocessOptions pre = calibrationPreprocessOptions();
            pre.minRssi_dBm = argMinRssi.getValue();
            FramePreparer preparer(array, pre);
            CalibratorOptions copt;
            copt.mode = splitter ? CalibrationMode::Splitter : CalibrationMode::Drive;
            copt.segment_s = argSegment.getValue();
            copt.robustScale = argRobust.getValue();
            PhaseCalibrator calibrator(array, copt);
            // Transmit chains: one calibrator per multi-antenna access point.
            std::map<MacAddress, PhaseCalibrator> txCalibrators;
            // The AP's view is less coherent than the receiver's: each stream's phase slope
            // is fitted on its own (cyclic shifts), and the fits differ a little under
            // multipath, which decorrelates the band edges. A segment counts as line of sight
            // at a lower coherence; the AoD errors on the drive are the real check.
            CalibratorOptions txOpt = copt;
            txOpt.losCoherence = 0.6;
            TransmitChainFramer framer;
            CalibrationFrame txFrame;
            if (txChains)
                for (const auto& mac : use)
                    if (siteOf.at(mac)->array->size() >= 2)
                        txCalibrators.emplace(mac, PhaseCalibrator(*siteOf.at(mac)->array, txOpt));
            std::map<uint32_t, std::vector<CalibrationFrame>> checkFrames;
            std::map<uint32_t, uint64_t> checkSeen;
            const uint64_t checkStride =
                std::max<uint64_t>(1, summary.csiFrames / 3000);  // enough for a verdict
            std::map<std::string, uint64_t> rejected;
            uint64_t noPose = 0, accepted = 0;
            // Per channel, the access points whose frames were used (the summary names a
            // channel left without calibration, and why).
            std::map<std::string, std::map<MacAddress, uint64_t>> usedOn;
            CalibrationFrame frame;
            cli::Progress p2("wifi-calibrate: reading", !argQuiet.getValue());
            readRawlog(
                input,
                [&](const CObservationWiFiCSI& obs)
                {
                    if (!use.count(obs.transmitter)) return;
                    if (onlyChannel && (obs.chanspec.centerChannel != onlyChannel->centerChannel ||
                                        obs.chanspec.bandwidthMHz != onlyChannel->bandwidthMHz))
                        return;
                    RejectReason r;
                    if (splitter)
                        r = preparer.prepareStatic(obs, frame);
                    else
                    {
                        mrpt::math::TPose2D robot;
                        if (!poses.at(mrpt::Clock::toDouble(obs.timestamp), robot))
                        {
                            ++noPose;
                            return;
                        }
                        r = preparer.prepare(obs, robot, txAt.at(obs.transmitter), frame);
                    }
                    if (r != RejectReason::Accepted)
                    {
                        ++rejected[toString(r)];
                        return;
                    }
                    ++accepted;
                    ++usedOn[frame.chanspec.asString()][obs.transmitter];
                    if (checking)
                    {
                        const uint32_t k = (uint32_t(frame.chanspec.centerChannel) << 16) |
                                           frame.chanspec.bandwidthMHz;
                        if (checkSeen[k]++ % checkStride == 0) checkFrames[k].push_back(frame);
                    }
                    else
                    {
                        calibrator.add(frame);
                        const auto tc = txCalibrators.find(obs.transmitter);
                        if (tc == txCalibrators.end()) return;
                        const TransmitterSite& site = *siteOf.at(obs.transmitter);
                        if (framer.make(
                                frame, {site.position.x, site.position.y, *site.yaw_rad},
                                unsigned(site.array->size()), txFrame))
                            tc->second.add(txFrame);
                    }
                },
                {}, [&](double f) { p2.update(f, std::to_string(accepted) + " frames"); });
            p2.done(std::to_string(accepted) + " frames");

            std::cout << "Input      : " << input << " (" << summary.csiFrames << " CSI frames, "
                      << summary.odometryReadings << " odometry readings)\n"
                      << "Array      : " << array.name << " (" << array.size() << " elements, "
                      << argArray.getValue() << ")\n"
                      << "Mode       : " << (splitter ? "static splitter" : "drive") << "\n"
                      << "Frames used: " << accepted;
            if (noPose) std::cout << ", " << noPose << " without a pose";
            for (const auto& [why, n] : rejected) std::cout << ", " << n << " " << why;
            std::cout << "\n";
            if (accepted == 0)
                throw std::runtime_error("no usable frames (see the rejection counts above)");

            // ---- Check mode --------------------------------------------------------------
            if (checking)
            {
                bool anyStale = false;
                for (const auto& [k, frames] : checkFrames)
                {
                    const Chanspec cs = frames.front().chanspec;
                    const PhaseCalibration* c =
                        checkStore->find(array.name, cs, frames.front().nRx);
                    std::cout << "\nChannel " << cs.asString() << "\n";
                    if (!c)
                    {
                        std::cout << "  no calibration for this channel in " << argCheck.getValue()
                                  << "\n";
                        continue;
                    }
                    if (splitter)
                        throw std::invalid_argument(
                            "--check needs a drive (not --static-splitter)");
                    const CheckResult r = calibrationResidual(frames, array, *c);
                    std::cout << "  calibration      : " << c->sourcePath << " (" << c->date
                              << ", residual " << fixed(c->residual_rad, 3) << " rad)\n"
                              << "  frames checked   : " << r.frames << "\n"
                              << "  bearing error    : median " << fixed(r.medianError_deg, 2)
                              << " deg, p90 " << fixed(r.p90Error_deg, 2)
                              << " deg (uncalibrated median "
                              << fixed(r.medianErrorUncalibrated_deg, 1) << " deg)\n"
                              << "  phase residual   : " << fixed(r.phaseResidual_rad, 3)
                              << " rad (limit " << fixed(r.residualLimit_rad, 3) << " rad)\n"
                              << "  verdict          : " << r.message << "\n";
                    if (r.stale)
                    {
                        anyStale = true;
                        std::cerr << "wifi-calibrate: " << cs.asString() << ": " << r.message
                                  << "\n";
                    }
                }
                return anyStale ? 3 : 0;
            }

            // ---- Calibrate each channel ---------------------------------------------------
            int rc = 0;
            std::map<std::string, std::string> outcome;  // channel -> written / why not
            if (calibrator.channels().empty())
                throw std::runtime_error(
                    "no frame could be grouped by the receive chains' jump states (a chain's "
                    "state never measurable): nothing to calibrate");
            for (const Chanspec& cs : calibrator.channels())
            {
                const ChannelCalibration res = calibrator.solve(cs);
                const auto& d = res.diag;
                const auto& c = res.calibration;
                std::cout << "\nChannel " << cs.asString() << " (" << c.antennas() << " antennas, "
                          << c.subcarriers.size() << " subcarriers)\n"
                          << "  frames           : " << d.frames << " in " << d.segments
                          << " segments over " << fixed(d.duration_s) << " s\n";
                if (!splitter)
                    std::cout << "  geometry         : " << d.bearingBins
                              << " bearing bins of 10 deg, 5-95% span "
                              << fixed(d.bearingSpan_deg, 0) << " deg, median distance "
                              << fixed(d.medianDistance_m, 2) << " m\n";
                std::cout << "  line of sight    : " << fixed(100 * d.losShare, 0)
                          << " % of frames explained (principal share "
                          << fixed(d.principalShare, 3) << ")\n"
                          << "  phase residual   : coarse " << fixed(d.coarseResidual_rad * kDeg, 2)
                          << " deg, refined " << fixed(d.residual_rad * kDeg, 2) << " deg RMS\n"
                          << "  Levenberg-Marq.  : " << d.iterations << " iterations, cost "
                          << std::setprecision(6) << d.initialCost << " -> " << d.finalCost << ", "
                          << fixed(d.solveTime_s, 2) << " s\n"
                          << "  antenna offsets  :";
                for (size_t i = 0; i < c.antennas(); ++i)
                    std::cout << " " << i << ":" << fixed(meanPhase(c.phases_rad[i]) * kDeg, 1)
                              << "deg";
                std::cout << "  (mean over subcarriers)\n  antenna gains    :";
                for (size_t i = 0; i < c.antennas(); ++i)
                    std::cout << " " << i << ":" << fixed(c.gainAt(i), 2) << "dB";
                std::cout << "\n";
                if (!d.chainStates.empty() || d.chainStateChanges > 0)
                {
                    // The 4366c0's chains jump among delay states: one set of offsets per state.
                    std::cout << "  chain states     : " << d.chainStateChanges << " changes, "
                              << d.unknownStateFrames
                              << " frames left out (a chain's state not measurable or too rare)\n";
                    if (d.mergedChainStates > 0)
                        std::cout << "    " << d.mergedChainStates
                                  << " more within 3/4 of a jump of their chain's reference "
                                     "(delay and phase): multipath, merged into it\n";
                    for (const auto& st : d.chainStates)
                        std::cout << "    chain " << st.antenna << " state " << int(st.state)
                                  << ": " << std::setw(6) << st.frames << " frames, delay "
                                  << signedFixed(st.delay_s * 1e9, 2) << " ns"
                                  << (st.reference
                                          ? " (reference)"
                                          : ", offset " + signedFixed(st.deltaDelay_s * 1e9, 2) +
                                                " ns " + signedFixed(st.deltaPhase_rad * kDeg, 1) +
                                                " deg")
                                  << "\n";
                }
                if (!res.bearingErrorAfter_deg.empty())
                    std::cout << "  bearing error    : median "
                              << fixed(quantile(res.bearingErrorBefore_deg, 0.5), 2) << " -> "
                              << fixed(quantile(res.bearingErrorAfter_deg, 0.5), 2) << " deg, p90 "
                              << fixed(quantile(res.bearingErrorBefore_deg, 0.9), 2) << " -> "
                              << fixed(quantile(res.bearingErrorAfter_deg, 0.9), 2) << " deg ("
                              << res.bearingErrorAfter_deg.size()
                              << " frames of the drive, Bartlett scan)\n";
                for (const auto& w : res.warnings)
                    std::cerr << "wifi-calibrate: warning: " << cs.asString() << ": " << w << "\n";
                const std::string path =
                    PhaseCalibration::pathFor(argOut.getValue(), array.name, cs);
                PhaseCalibration toWrite = c;
                const std::string policy = applyChainStatePolicy(toWrite, chainStatePolicy);
                if (!policy.empty()) std::cout << "  chain states     : " << policy << "\n";
                if (res.determined() || argForce.getValue())
                {
                    toWrite.saveYamlFile(path);
                    std::cout << "  written          : " << path
                              << (res.determined() ? "" : " (forced despite the warnings)") << "\n";
                    outcome[cs.asString()] = "written " + path;
                }
                else
                {
                    std::cout << "  NOT written      : " << path
                              << " (the drive cannot determine the calibration, see the warnings;"
                                 " --force writes it anyway)\n";
                    rc = 2;
                    outcome[cs.asString()] =
                        "NOT written: " +
                        (res.warnings.empty() ? std::string("see above") : res.warnings.front());
                }
                if (argReport.isSet())
                    for (const auto& png : writeCalibrationReport(res, argReport.getValue()))
                        std::cout << "  report           : " << png << "\n";
            }

            // ---- Every channel of the recording, with the access points used there --------
            std::map<std::string, std::map<MacAddress, uint64_t>> heardOn;
            for (const auto& [mac, src] : summary.transmitters)
                for (const auto& [cs, n] : src.channels) heardOn[cs][mac] += n;
            if (heardOn.size() > 1 || outcome.size() > 1)
            {
                std::cout << "\nChannels (" << heardOn.size() << " in the recording):\n";
                for (const auto& [cs, macs] : heardOn)
                {
                    if (onlyChannel && !Chanspec::fromString(cs).sameChannel(*onlyChannel))
                        continue;
                    std::string aps;
                    for (const auto& [mac, n] : usedOn[cs])
                        aps += (aps.empty() ? "" : ", ") + mac.asString() + " (" +
                               std::to_string(n) + " frames)";
                    const auto it = outcome.find(cs);
                    std::string line;
                    if (it != outcome.end())
                        line = it->second + "; from " + std::to_string(usedOn[cs].size()) +
                               " access point" + (usedOn[cs].size() == 1 ? "" : "s") + ": " + aps;
                    else
                    {
                        // Heard, but nothing to calibrate it from: say which APs and why.
                        std::string heard, unlisted;
                        for (const auto& [mac, n] : macs)
                        {
                            heard += (heard.empty() ? "" : ", ") + mac.asString() + " (" +
                                     std::to_string(n) + " frames)";
                            if (!use.count(mac))
                                unlisted += (unlisted.empty() ? "" : ", ") + mac.asString();
                        }
                        line = "NOT calibrated: heard " + heard + "; " +
                               (!unlisted.empty()
                                    ? "not used (not in --transmitters, or another --mac): " +
                                          unlisted + "; add their positions to calibrate " + cs
                                    : "every frame was rejected (see the counts above)");
                        std::cerr << "wifi-calibrate: channel " << cs << ": " << line << "\n";
                    }
                    std::cout << "  " << std::setw(8) << std::left << cs << std::right << ": "
                              << line << "\n";
                }
            }

            // ---- Transmit chains of each access point ---------------------------------------
            for (const auto& [mac, tcal] : txCalibrators)
            {
                const TransmitterSite& site = *siteOf.at(mac);
                if (tcal.channels().empty())
                {
                    std::cerr << "wifi-calibrate: warning: transmitter " << mac.asString() << " ("
                              << site.name << "): no frame with all " << site.array->size()
                              << " streams: its transmit chains are not calibrated\n";
                    rc = std::max(rc, 2);
                    continue;
                }
                for (const Chanspec& cs : tcal.channels())
                {
                    ChannelCalibration res = tcal.solve(cs);
                    PhaseCalibration& c = res.calibration;
                    c.role = PhaseCalibration::Role::Transmitter;
                    c.transmitter = mac;
                    c.method =
                        "wifi-calibrate --transmit-chains (receiver's method mirrored at the AP: "
                        "per-subcarrier PCA + Ceres LM, Cauchy loss)";
                    // What the calibration leaves on its own drive: a robust RMS of the AoD
                    // errors (1.4826 · median |e|), added to every AoD σ by csi-bearings.
                    if (!res.bearingErrorAfter_deg.empty())
                        c.aodResidual_rad =
                            1.4826 * quantile(res.bearingErrorAfter_deg, 0.5) / kDeg;
                    const auto& d = res.diag;
                    std::cout << "\nTransmitter " << mac.asString() << " (" << site.name << ", "
                              << site.array->name << ") on " << cs.asString() << ": "
                              << c.antennas() << " transmit chains\n"
                              << "  frames           : " << d.frames << " in " << d.segments
                              << " segments, " << d.bearingBins << " AoD bins of 10 deg, median "
                              << "distance " << fixed(d.medianDistance_m, 2) << " m\n"
                              << "  line of sight    : " << fixed(100 * d.losShare, 0)
                              << " % of frames explained, phase residual "
                              << fixed(d.residual_rad * kDeg, 2) << " deg RMS\n"
                              << "  chain offsets    :";
                    for (size_t i = 0; i < c.antennas(); ++i)
                        std::cout << " " << i << ":" << fixed(meanPhase(c.phases_rad[i]) * kDeg, 1)
                                  << "deg";
                    std::cout << "\n";
                    if (!res.bearingErrorAfter_deg.empty())
                        std::cout << "  AoD error        : median "
                                  << fixed(quantile(res.bearingErrorBefore_deg, 0.5), 2) << " -> "
                                  << fixed(quantile(res.bearingErrorAfter_deg, 0.5), 2)
                                  << " deg, p90 "
                                  << fixed(quantile(res.bearingErrorBefore_deg, 0.9), 2) << " -> "
                                  << fixed(quantile(res.bearingErrorAfter_deg, 0.9), 2)
                                  << " deg on the drive (residual for sigma "
                                  << fixed(c.aodResidual_rad * kDeg, 2) << " deg)\n";
                    for (const auto& w : res.warnings)
                        std::cerr << "wifi-calibrate: warning: " << mac.asString() << " "
                                  << cs.asString() << ": " << w << "\n";
                    const std::string path =
                        PhaseCalibration::transmitterPathFor(argOut.getValue(), mac, cs);
                    if (res.determined() || argForce.getValue())
                    {
                        c.saveYamlFile(path);
                        std::cout << "  written          : " << path
                                  << (res.determined() ? "" : " (forced despite the warnings)")
                                  << "\n";
                    }
                    else
                    {
                        std::cout << "  NOT written      : " << path
                                  << " (the drive cannot determine it, see the warnings)\n";
                        rc = 2;
                    }
                }
            }
            return rc;
        });
}
