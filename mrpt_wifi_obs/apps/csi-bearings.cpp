/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * csi-bearings: runs a bearing estimator over the CSI of a rawlog and writes a rawlog with the
 * original objects plus, after every CSI observation that gave a bearing,
 * mrpt_wifi::CObservationWiFiBearing, mrpt::obs::CObservationBearingRange and (optionally)
 * CObservationImage pictures; optionally a CSV and PNG files. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/datetime.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/obs/ConfigPaths.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/RawlogReader.h>
#include <mrpt_wifi/obs/bearing/BearingChainConfig.h>
#include <mrpt_wifi/obs/bearing/BearingImages.h>
#include <mrpt_wifi/obs/bearing/BearingProcessor.h>

#include <algorithm>
#include <array>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

using namespace mrpt_wifi;
namespace fs = std::filesystem;

namespace
{
/** A file of the installed data folder (any --prefix) or the source tree's share/. */
std::string findShareFile(const std::string& relative)
{
    try
    {
        return config::findDataFile(relative);
    }
    catch (const std::invalid_argument& e)
    {
        throw std::runtime_error(std::string(e.what()) + "; pass --array FILE");
    }
}

/** A TUM trajectory file: (time [s], planar pose) per line, sorted by time. */
std::vector<std::pair<double, mrpt::math::TPose2D>> readTumPoses(const std::string& path)
{
    std::ifstream f(path);
    if (!f) throw std::runtime_error("cannot open odometry file '" + path + "'");
    std::vector<std::pair<double, mrpt::math::TPose2D>> out;
    std::string line;
    for (int n = 1; std::getline(f, line); ++n)
    {
        if (line.empty() || line[0] == '#') continue;
        std::istringstream is(line);
        double t, x, y, z, qx, qy, qz, qw;
        if (!(is >> t >> x >> y >> z >> qx >> qy >> qz >> qw))
            throw std::runtime_error(
                path + ":" + std::to_string(n) + ": expected 't x y z qx qy qz qw'");
        const double yaw = std::atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz));
        if (!out.empty() && t < out.back().first)
            throw std::runtime_error(path + ":" + std::to_string(n) + ": time goes backwards");
        out.emplace_back(t, mrpt::math::TPose2D(x, y, yaw));
    }
    if (out.empty()) throw std::runtime_error("odometry file '" + path + "' holds no pose");
    return out;
}

double median(std::vector<double> v)
{
    if (v.empty()) return NAN;
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
}

/** Options file: {preprocess: {...}, window: {...}, estimators: {NAME: {...}}}. */
using ConfigFile = bearing::BearingChainConfig;
ConfigFile loadConfig(const std::string& path, const std::string& algo)
{
    return bearing::loadBearingChainConfig(path, algo);
}

struct TransmitterStats
{
    uint64_t frames = 0, bearings = 0;
    std::vector<double> aoa_deg, quality;
    uint64_t aodEstimated = 0, aodEmitted = 0;  //!< estimator found one / passed the gate
    uint64_t aodCalibrated = 0;                 //!< emitted with a transmit-chain calibration
    unsigned imagesWritten = 0;
};
}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "csi-bearings",
        [&]
        {
            std::string algoList;
            for (const auto& n : bearing::estimatorNames())
                algoList += (algoList.empty() ? "" : "|") + n;
            TCLAP::CmdLine cmd(
                "Estimates WiFi bearings (AoA, AoD) from the CSI observations of a rawlog and "
                "writes a rawlog with the original objects plus mrpt_wifi::CObservationWiFiBearing "
                "and mrpt::obs::CObservationBearingRange after each CSI frame that gave one. "
                "Captures (pcap, .dat, ESP32 lines, ROS bags): convert them with csi-import first.",
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argIn(
                "input", "Input rawlog with CObservationWiFiCSI", true, "", "IN.rawlog", cmd);
            TCLAP::UnlabeledValueArg<std::string> argOut(
                "output", "Output rawlog", true, "", "OUT.rawlog", cmd);
            TCLAP::ValueArg<std::string> argAlgo(
                "a", "algo",
                "Estimator: " + algoList + " (default: 'default', the recommended one)", false,
                "default", "NAME", cmd);
            TCLAP::ValueArg<std::string> argOdomTum(
                "", "odometry-tum",
                "Robot odometry as a TUM trajectory (t x y z qx qy qz qw, same clock as the CSI), "
                "for rawlogs without CObservationOdometry (replaces the rawlog's odometry). With "
                "odometry each window combines only frames taken while the robot moved little",
                false, "", "FILE", cmd);
            TCLAP::SwitchArg argNoOdometry(
                "", "no-odometry",
                "Ignore the rawlog's CObservationOdometry, as on a robot without odometry: each "
                "window combines only the frames of its last window.max_span_without_odometry_s "
                "(wifi-localize's chain without odometry does the same)",
                cmd);
            TCLAP::ValueArg<std::string> argCalib(
                "c", "calib",
                "Phase calibration: a file (one channel) or a folder "
                "DIR/<device>/ch<C>_<BW>mhz.yaml",
                false, "", "FILE|DIR", cmd);
            TCLAP::ValueArg<std::string> argArray(
                "", "array", "Receive array: a file, or a shipped one by name (default: rt-ac86u)",
                false, "", "FILE", cmd);
            TCLAP::MultiArg<std::string> argTxArray(
                "", "tx-array",
                "Transmitter array for AoD: FILE (all transmitters) or MAC=FILE; repeatable", false,
                "[MAC=]FILE", cmd);
            TCLAP::ValueArg<std::string> argConfig(
                "", "config",
                "YAML options: preprocess / window / estimators.NAME (see share/bearings/)", false,
                "", "FILE", cmd);
            TCLAP::MultiArg<std::string> argParam(
                "p", "param", "Estimator option KEY=VALUE (overrides --config); repeatable", false,
                "KEY=VALUE", cmd);
            TCLAP::ValueArg<double> argMinRssi(
                "", "min-rssi", "Reject frames below this RSSI [dBm]", false, -127, "DBM", cmd);
            TCLAP::ValueArg<unsigned> argStride(
                "", "stride", "Estimate every N-th accepted frame per transmitter", false, 0, "N",
                cmd);
            TCLAP::SwitchArg argRequireCalib(
                "", "require-calib", "Reject frames on channels without calibration", cmd);
            TCLAP::SwitchArg argUncalibratedAod(
                "", "uncalibrated-aod",
                "Report AoD also for transmitters whose transmit chains are not calibrated "
                "(wifi-calibrate --transmit-chains); such angles are off by tens of degrees on "
                "real access points",
                cmd);
            TCLAP::ValueArg<std::string> argTracking(
                "", "tracking",
                "Per-transmitter tracking over time (on/off; default: on for the default "
                "estimator): a window's bearing near one endfire that the transmitter's track "
                "puts at the other is replaced by that one",
                false, "", "on|off", cmd);
            TCLAP::ValueArg<std::string> argStateVerification(
                "", "state-verification",
                "Receive-chain jump states learnt online keep being checked against the other "
                "chains: refined, confirmed, or dropped and learnt again; until confirmed their "
                "bearings' sigma covers the doubt (on/off; default: on)",
                false, "on", "on|off", cmd);
            TCLAP::ValueArg<std::string> argSaveLearntStates(
                "", "save-learnt-states",
                "Write the receive calibration with the jump states learnt (and confirmed) "
                "during this run added, as DIR/<device>/ch<C>_<BW>mhz.yaml: with --calib DIR "
                "the next run knows them",
                false, "", "DIR", cmd);
            TCLAP::ValueArg<std::string> argCsv(
                "", "csv", "Also write the bearings as CSV", false, "", "FILE", cmd);
            TCLAP::ValueArg<std::string> argImages(
                "", "images", "Write PNG pictures (CSI magnitude/phase, bearing profile) into DIR",
                false, "", "DIR", cmd);
            TCLAP::ValueArg<unsigned> argImageEvery(
                "", "image-every", "Pictures for every N-th bearing of each transmitter", false,
                100, "N", cmd);
            TCLAP::SwitchArg argRawlogImages(
                "", "rawlog-images",
                "Also put the pictures into the output rawlog as CObservationImage", cmd);
            TCLAP::SwitchArg argNoBR(
                "", "no-bearing-range", "Do not add CObservationBearingRange", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress display", cmd);
            if (const int rc = cli::parseCommandLine(cmd, argc, const_cast<const char**>(argv));
                rc >= 0)
                return rc;

            // ---- everything that can be wrong with the arguments, before any work
            if (argNoOdometry.getValue() && argOdomTum.isSet())
                throw std::invalid_argument("--no-odometry and --odometry-tum exclude each other");
            const std::string algo = argAlgo.getValue();
            ConfigFile cfg = loadConfig(argConfig.getValue(), algo);
            mrpt::containers::yaml params = mrpt::containers::yaml::Map();
            if (!cfg.estimatorParams.isNullNode()) params = cfg.estimatorParams;
            for (const auto& kv : argParam.getValue())
            {
                const auto eq = kv.find('=');
                if (eq == std::string::npos || eq == 0)
                    throw std::invalid_argument("--param '" + kv + "': expected KEY=VALUE");
                const std::string key = kv.substr(0, eq);
                const auto doc = mrpt::containers::yaml::FromText(key + ": " + kv.substr(eq + 1));
                params[key] = doc[key];
            }
            auto estimator = bearing::createEstimator(algo, params);  // unknown name/option: throws
            if (argImages.isSet() || argRawlogImages.getValue())
                estimator->options().keepProfile = true;

            AntennaArray rxArray =
                argArray.isSet()
                    ? AntennaArray::fromFileOrName(argArray.getValue(), "--array")
                    : AntennaArray::fromYamlFile(findShareFile("arrays/rt-ac86u.yaml"));
            CalibrationStore calib;
            if (argCalib.isSet()) calib = CalibrationStore::open(argCalib.getValue());
            PreprocessOptions pre = cfg.pre;
            if (argMinRssi.isSet()) pre.minRssi_dBm = argMinRssi.getValue();
            if (argRequireCalib.getValue()) pre.requireCalibration = true;
            if (argStride.isSet()) cfg.window.stride = std::max(1u, argStride.getValue());
            if (argUncalibratedAod.getValue()) cfg.window.uncalibratedAod = true;
            if (argTracking.isSet())
            {
                const std::string& t = argTracking.getValue();
                if (t != "on" && t != "off")
                    throw std::invalid_argument("--tracking: 'on' or 'off', not '" + t + "'");
                cfg.window.tracking = t == "on";
            }
            {
                const std::string& v = argStateVerification.getValue();
                if (v != "on" && v != "off")
                    throw std::invalid_argument(
                        "--state-verification: 'on' or 'off', not '" + v + "'");
                pre.chainStates.verify = v == "on";
            }
            if (argSaveLearntStates.isSet() && !argCalib.isSet())
                throw std::invalid_argument(
                    "--save-learnt-states needs --calib (the calibration the states are added to)");
            CsiPreprocessor preprocessor(pre, rxArray, calib);

            bearing::BearingProcessor processor(
                std::move(preprocessor), std::move(estimator), cfg.window);
            for (const auto& t : argTxArray.getValue())
            {
                const auto eq = t.find('=');
                if (eq == std::string::npos)
                    processor.setDefaultTransmitterArray(
                        AntennaArray::fromFileOrName(t, "--tx-array"));
                else
                    processor.setTransmitterArray(
                        MacAddress::fromString(t.substr(0, eq)),
                        AntennaArray::fromFileOrName(t.substr(eq + 1), "--tx-array"));
            }

            std::vector<std::pair<double, mrpt::math::TPose2D>> tumOdometry;
            if (argOdomTum.isSet()) tumOdometry = readTumPoses(argOdomTum.getValue());
            size_t nextTum = 0;
            uint64_t odometryUsed = 0;

            // ---- pre-scan: channels and antenna counts must fit the array and calibration
            cli::Progress progress("csi-bearings", !argQuiet.getValue());
            // Frames per (channel, receive cores): a channel is refused only when none of its
            // shapes fits (the first frame of a transmitter may lack a core lost on the way).
            std::map<uint16_t, std::map<std::pair<unsigned, std::vector<uint8_t>>, uint64_t>>
                shapes;
            uint64_t csiTotal = 0;
            forEachRawlogObject(
                argIn.getValue(),
                [&](mrpt::serialization::CSerializable::Ptr& obj)
                {
                    const auto visit = [&](const mrpt::obs::CObservation::Ptr& o)
                    {
                        if (auto c = std::dynamic_pointer_cast<CObservationWiFiCSI>(o))
                        {
                            ++csiTotal;
                            ++shapes[c->chanspec.raw][{c->nRx, c->rxCores}];
                        }
                    };
                    if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj))
                        for (const auto& o : *sf) visit(o);
                    else if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj))
                        visit(o);
                },
                [&](double f) { progress.update(f, "checking input"); });
            if (csiTotal == 0)
                throw std::runtime_error("'" + argIn.getValue() + "' holds no CObservationWiFiCSI");
            // Every channel at once, each with its own calibration: one missing is named with
            // what to run (an error with --require-calib, else its bearings are uncalibrated).
            std::string missingChannels;
            for (const auto& [raw, byCores] : shapes)
            {
                const auto cs = Chanspec::decode(raw);
                if (!cs || calib.empty() || !calib.isFolder()) continue;
                const std::string& device = processor.preprocessor().rxArray().name;
                uint64_t frames = 0;
                bool found = false;
                for (const auto& [shape, n] : byCores)
                {
                    frames += n;
                    try
                    {
                        found |= calib.find(device, *cs, shape.first) != nullptr;
                    }
                    catch (const CalibrationError&)
                    {
                        found = true;  // present but unfit: checkCompatible names it below
                    }
                }
                if (found) continue;
                const std::string advice = calib.missingChannelAdvice(device, *cs);
                if (argRequireCalib.getValue())
                    missingChannels += "\n  " + std::to_string(frames) + " frames on " +
                                       cs->asString() + ": " + advice;
                else
                    std::cerr << "csi-bearings: warning: " << frames << " frames on "
                              << cs->asString() << " get uncalibrated bearings: " << advice << "\n";
            }
            if (!missingChannels.empty())
                throw std::runtime_error(
                    "--require-calib and channels without calibration:" + missingChannels);
            for (const auto& [raw, byCores] : shapes)
            {
                const auto cs = Chanspec::decode(raw);
                if (!cs) continue;
                std::vector<std::pair<uint64_t, std::pair<unsigned, std::vector<uint8_t>>>> ranked;
                for (const auto& [shape, n] : byCores) ranked.emplace_back(n, shape);
                std::sort(ranked.rbegin(), ranked.rend());
                std::exception_ptr firstError;
                for (const auto& [n, shape] : ranked)
                {
                    try
                    {
                        // Throws with a clear message.
                        processor.preprocessor().checkCompatible(*cs, shape.first, shape.second);
                        firstError = nullptr;
                        break;
                    }
                    catch (...)
                    {
                        if (!firstError) firstError = std::current_exception();
                    }
                }
                if (firstError) std::rethrow_exception(firstError);
            }

            // ---- processing
            mrpt::io::CFileGZOutputStream out;
            if (!out.open(argOut.getValue()))
                throw std::runtime_error("cannot create rawlog '" + argOut.getValue() + "'");
            auto archive = mrpt::serialization::archiveFrom(out);
            std::ofstream csv;
            if (argCsv.isSet())
            {
                csv.open(argCsv.getValue());
                if (!csv) throw std::runtime_error("cannot create '" + argCsv.getValue() + "'");
                csv << "timestamp,transmitter,channel,rssi_dbm,algorithm,aoa_deg,aoa_std_deg,"
                       "aoa_ambiguous,aoa_mirror_deg,has_aod,aod_deg,aod_std_deg,aod_mirror_deg,"
                       "delay_ns,quality,frames,aoa_alt_deg,aoa_alt_weight,aoa_direction_std_deg,"
                       "aoa_more_alts\n";
                csv << std::fixed;
            }
            if (argImages.isSet()) fs::create_directories(argImages.getValue());

            std::map<MacAddress, TransmitterStats> stats;
            std::map<std::string, uint64_t> peerRecordingFrames;  //!< by sensor label
            std::array<uint64_t, kRejectReasonCount> rejected{};
            std::vector<std::string> chainStateNotices;
            uint64_t csiSeen = 0, bearingsTotal = 0, imagesTotal = 0;
            const double toDeg = 180.0 / M_PI;

            // Returns what to add after one CSI observation.
            const auto handleOdometry = [&](const mrpt::obs::CObservation::Ptr& o)
            {
                if (argOdomTum.isSet() || argNoOdometry.getValue()) return;
                if (auto od = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o))
                {
                    processor.addOdometry(od->timestamp, od->odometry.asTPose());
                    ++odometryUsed;
                }
            };
            const auto handle =
                [&](const CObservationWiFiCSI& c, std::vector<mrpt::obs::CObservation::Ptr>& extra)
            {
                ++csiSeen;
                // TUM odometry: everything up to a little after this frame.
                const double tc = mrpt::Clock::toDouble(c.timestamp);
                for (; nextTum < tumOdometry.size() && tumOdometry[nextTum].first <= tc + 0.1;
                     ++nextTum, ++odometryUsed)
                    processor.addOdometry(
                        mrpt::Clock::fromDouble(tumOdometry[nextTum].first),
                        tumOdometry[nextTum].second);
                // A peer's recording of this robot (estimator sar) is input, not a transmitter:
                // the processor keeps it and gives no bearing for it.
                if (cfg.window.peerRecordings.count(c.sensorLabel))
                    ++peerRecordingFrames[c.sensorLabel];
                else
                    ++stats[c.transmitter].frames;
                RejectReason why;
                auto b = processor.process(c, &why);
                if (why != RejectReason::Accepted) ++rejected[size_t(why)];
                for (auto& n : processor.preprocessor().takeChainStateNotices())
                    chainStateNotices.push_back(std::move(n));
                if (!b) return;
                auto& st = stats[c.transmitter];
                ++bearingsTotal;
                ++st.bearings;
                st.aoa_deg.push_back(b->aoa_rad * toDeg);
                st.quality.push_back(b->quality);
                if (processor.lastResult().hasAod) ++st.aodEstimated;
                if (b->hasAod) ++st.aodEmitted;
                if (b->hasAod && processor.lastFrame()->txCalibration) ++st.aodCalibrated;
                extra.push_back(b);
                if (!argNoBR.getValue()) extra.push_back(b->asBearingRange());
                if (csv.is_open())
                {
                    // What was not measured is an empty cell, never a 0 that reads as an angle.
                    const auto deg = [&](bool measured, double rad)
                    {
                        std::ostringstream cell;
                        if (measured) cell << std::fixed << std::setprecision(3) << rad * toDeg;
                        return cell.str();
                    };
                    csv << std::setprecision(6) << mrpt::Clock::toDouble(b->timestamp) << ","
                        << b->transmitter.asString() << "," << b->chanspec.asString() << ","
                        << int(b->rssi_dBm) << "," << b->algorithm << "," << std::setprecision(3)
                        << b->aoa_rad * toDeg << "," << b->aoaStd_rad * toDeg << ","
                        << int(b->aoaAmbiguous) << "," << deg(b->aoaAmbiguous, b->aoaMirror_rad)
                        << "," << int(b->hasAod) << "," << deg(b->hasAod, b->aod_rad) << ","
                        << deg(b->hasAod, b->aodStd_rad) << ","
                        << deg(b->hasAod && b->aodAmbiguous, b->aodMirror_rad) << ","
                        << b->delay_s * 1e9 << "," << b->quality << "," << b->framesUsed << ","
                        << deg(b->hasAoaAlternative, b->aoaAlternative_rad) << ","
                        << (b->hasAoaAlternative ? std::to_string(b->aoaAlternativeWeight) : "")
                        << "," << deg(b->hasAoaAlternative, b->aoaDirectionStd_rad) << ",";
                    // The second and later alternatives: "deg:weight;deg:weight".
                    for (size_t i = 0; b->hasAoaAlternative && i < b->moreAoaAlternatives.size();
                         ++i)
                        csv << (i ? ";" : "") << deg(true, b->moreAoaAlternatives[i].aoa_rad) << ":"
                            << std::setprecision(4) << b->moreAoaAlternatives[i].weight;
                    csv << "\n";
                }
                const bool picture =
                    (argImages.isSet() || argRawlogImages.getValue()) &&
                    (st.bearings - 1) % std::max(1u, argImageEvery.getValue()) == 0;
                if (!picture) return;
                const auto* prof = processor.estimator().lastProfile();
                std::string mac = c.transmitter.asString();
                std::replace(mac.begin(), mac.end(), ':', '-');
                const mrpt::img::CImage csiImg =
                    bearing::renderMagnitudePhase(*processor.lastFrame());
                mrpt::img::CImage profImg;
                if (prof)
                    profImg = bearing::renderBearingProfile(
                        *prof, processor.lastResult(),
                        algo + ": " + prof->label + "  " + c.transmitter.asString());
                if (argImages.isSet())
                {
                    const std::string stem = (fs::path(argImages.getValue()) /
                                              (mac + "_" + std::to_string(st.bearings - 1)))
                                                 .string();
                    csiImg.saveToFile(stem + "_csi.png");
                    if (prof) profImg.saveToFile(stem + "_profile.png");
                    imagesTotal += prof ? 2 : 1;
                }
                if (argRawlogImages.getValue())
                {
                    extra.push_back(bearing::asImageObservation(
                        csiImg, c.timestamp, c.sensorLabel + "_CSI_PLOT"));
                    if (prof)
                        extra.push_back(bearing::asImageObservation(
                            profImg, c.timestamp, c.sensorLabel + "_PROFILE"));
                }
            };

            std::vector<mrpt::obs::CObservation::Ptr> extra;
            forEachRawlogObject(
                argIn.getValue(),
                [&](mrpt::serialization::CSerializable::Ptr& obj)
                {
                    if (auto sf = std::dynamic_pointer_cast<mrpt::obs::CSensoryFrame>(obj))
                    {
                        // Sensory-frame rawlogs: the new observations join the same frame.
                        std::vector<mrpt::obs::CObservation::Ptr> added;
                        for (const auto& o : *sf)
                        {
                            handleOdometry(o);
                            if (auto c = std::dynamic_pointer_cast<CObservationWiFiCSI>(o))
                            {
                                extra.clear();
                                handle(*c, extra);
                                added.insert(added.end(), extra.begin(), extra.end());
                            }
                        }
                        for (auto& a : added) sf->insert(a);
                        archive << *sf;
                        return;
                    }
                    archive << *obj;
                    if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservation>(obj))
                        handleOdometry(o);
                    if (auto c = std::dynamic_pointer_cast<CObservationWiFiCSI>(obj))
                    {
                        extra.clear();
                        handle(*c, extra);
                        for (const auto& e : extra) archive << *e;
                    }
                },
                [&](double f)
                {
                    progress.update(
                        f, std::to_string(csiSeen) + "/" + std::to_string(csiTotal) + " frames, " +
                               std::to_string(bearingsTotal) + " bearings");
                });
            progress.done(std::to_string(bearingsTotal) + " bearings");
            out.close();

            // ---- summary
            std::string odometryLine;
            if (odometryUsed > 0)
                odometryLine = std::to_string(odometryUsed) + " poses from " +
                               (argOdomTum.isSet() ? argOdomTum.getValue() : "the rawlog");
            else
            {
                std::ostringstream o;
                o << "none (" << (argNoOdometry.getValue() ? "--no-odometry: " : "");
                const double span = cfg.window.maxWindowSpanWithoutOdometry_s;
                if (span > 0)
                    o << "windows of the last " << span << " s)";
                else
                    o << "windows by age only)";
                odometryLine = o.str();
            }
            std::cout << "Input : " << argIn.getValue() << " (" << csiSeen << " CSI frames)\n"
                      << "Array : " << rxArray.name << " (" << rxArray.sourcePath << ")"
                      << (rxArray.isLinear() ? ", linear: AoA has a mirror candidate" : "") << "\n"
                      << "Calib : " << (calib.empty() ? "none (uncalibrated)" : calib.path())
                      << "\n"
                      << "Algo  : " << algo << "\n"
                      << "Odometry: " << odometryLine << "\n"
                      << "Output: " << argOut.getValue() << " (" << bearingsTotal << " bearings)\n";
            std::cout << "Bearings per transmitter:\n"
                      << "  transmitter        frames  bearings  median AoA[deg]  median quality\n";
            for (const auto& [mac, s] : stats)
                std::cout << "  " << mac.asString() << "  " << std::setw(6) << s.frames << "  "
                          << std::setw(8) << s.bearings << "  " << std::setw(15) << std::fixed
                          << std::setprecision(1) << median(s.aoa_deg) << "  " << std::setw(14)
                          << std::setprecision(2) << median(s.quality) << "\n";
            for (const auto& [label, frames] : peerRecordingFrames)
                std::cout << "  " << label << ": " << frames << " frames of peer "
                          << cfg.window.peerRecordings.at(label).asString()
                          << "'s recording of this robot (synthetic aperture input)\n";
            for (const auto& [mac, s] : stats)
                if (s.aodEstimated > s.aodEmitted)
                    std::cout << "  " << mac.asString() << ": no AoD (" << s.aodEstimated
                              << " dropped): its transmit chains are not calibrated in "
                              << (calib.isFolder() ? calib.path() : std::string("--calib DIR"))
                              << " (wifi-calibrate --transmit-chains; --uncalibrated-aod "
                                 "reports them anyway)\n";
                else if (s.aodEmitted > 0)
                    std::cout << "  " << mac.asString() << ": AoD "
                              << (s.aodCalibrated == s.aodEmitted
                                      ? "with its transmit-chain calibration"
                                      : "uncalibrated (--uncalibrated-aod)")
                              << "\n";
            uint64_t rejectedTotal = 0;
            for (auto r : rejected) rejectedTotal += r;
            std::cout << "Rejected frames: " << rejectedTotal << "\n";
            for (size_t i = 1; i < kRejectReasonCount; ++i)
                if (rejected[i])
                    std::cout << "  " << toString(RejectReason(i)) << ": " << rejected[i] << "\n";
            // The 4366c0's receive chains jump among delay states (issue 21).
            const auto trackers = processor.preprocessor().chainStateTrackers();
            if (!trackers.empty())
            {
                std::cout << "Receive chain states: "
                          << processor.preprocessor().chainStateChanges() << " changes";
                const bool applied = std::any_of(
                    trackers.begin(), trackers.end(), [](auto* t) { return t->applies(); });
                const bool delayOnly = std::any_of(
                    trackers.begin(), trackers.end(),
                    [](auto* t) { return t->delayOnlyCalibration(); });
                std::cout << (applied ? " (corrected with the calibration's per-state offsets)"
                              : delayOnly
                                  ? " (reported only: its calibration found the states "
                                    "differ by a delay alone, which the offsets hold through)"
                              : calib.empty() ? " (reported only: no calibration)"
                                              : " (reported only: the calibration holds no states; "
                                                "wifi-calibrate makes one that does)")
                          << "\n";
                for (const auto* t : trackers) std::cout << t->summary();
            }
            for (const auto& n : chainStateNotices) std::cerr << "warning: " << n << "\n";
            if (argSaveLearntStates.isSet())
            {
                const auto learnt = processor.preprocessor().calibrationsWithLearntStates();
                if (learnt.empty())
                    std::cout << "Learnt states: none confirmed; nothing written to "
                              << argSaveLearntStates.getValue() << "\n";
                for (const auto& c : learnt)
                {
                    const std::string path = PhaseCalibration::pathFor(
                        argSaveLearntStates.getValue(), c.device, c.chanspec);
                    fs::create_directories(fs::path(path).parent_path());
                    c.saveYamlFile(path);
                    std::cout << "Learnt states: " << path << " (" << c.chainStates.size()
                              << " states)\n";
                }
            }
            if (argImages.isSet())
                std::cout << "Images: " << imagesTotal << " PNG files in " << argImages.getValue()
                          << "\n";
            if (csv.is_open()) std::cout << "CSV   : " << argCsv.getValue() << "\n";
            if (bearingsTotal == 0)
            {
                // No result is a failure a script must see, with the reason that dominated.
                const size_t worst = size_t(
                    std::max_element(rejected.begin() + 1, rejected.end()) - rejected.begin());
                std::cerr << "csi-bearings: no bearing from the " << csiSeen << " CSI frames of '"
                          << argIn.getValue() << "'";
                if (rejected[worst] > 0)
                    std::cerr << ": " << rejected[worst] << " rejected as '"
                              << toString(RejectReason(worst)) << "' (see the summary above)";
                std::cerr << "\n";
                return cli::kExitNoBearings;
            }
            return 0;
        });
}
