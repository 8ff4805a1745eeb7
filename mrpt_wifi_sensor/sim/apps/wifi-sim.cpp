/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-sim: simulates a robot overhearing WiFi transmitters in a scenario file and writes what
 * a real recording would hold (a rawlog of CObservationWiFiCSI + CObservationOdometry, and
 * optionally the Nexmon datagrams as a pcap), plus the ground truth. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/obs/ConfigPaths.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>
#include <mrpt_wifi/sensor/PcapIO.h>
#include <mrpt_wifi/sim/GroundTruthWriter.h>
#include <mrpt_wifi/sim/RandomRoom.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

using namespace mrpt_wifi;

namespace
{
/** share/arrays of the installation (any --prefix) or of the source tree (ConfigPaths.h). */
std::string arraysDir()
{
    return std::filesystem::path(config::findDataFile("arrays/rt-ac86u.yaml"))
        .parent_path()
        .string();
}
}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "wifi-sim",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Simulates a robot with an RT-AC86U overhearing WiFi transmitters in a scenario "
                "(share/scenarios/*.yaml, keys in share/scenarios/README.md). Writes a rawlog of "
                "mrpt_wifi::CObservationWiFiCSI and CObservationOdometry timestamped as a real "
                "recording, optionally the Nexmon datagrams as a pcap, and the ground truth "
                "(TUM trajectory, transmitters, per-frame AoA/AoD/delay/SNR, impairments).",
                ' ', "0.1");
            TCLAP::UnlabeledMultiArg<std::string> argFiles(
                "files", "SCENARIO.yaml OUT.rawlog, or only OUT.rawlog with --random-room", true,
                "[SCENARIO.yaml] OUT.rawlog", cmd);
            TCLAP::ValueArg<uint32_t> argRandomRoom(
                "", "random-room",
                "Instead of a scenario file, random room number SEED (share/scenarios/README.md, "
                "'Random rooms'; seeds < 1000 are for development, >= 1000 for evaluation)",
                false, 0, "SEED", cmd);
            TCLAP::ValueArg<std::string> argReceiver(
                "", "receiver",
                "With --random-room: the robot's receiver, rt-ac86u (default: 4 antennas, 155/80, "
                "every bin) or intel5300 (share/arrays/intel5300-linear-3.yaml, 159/40, the Intel "
                "5300's 30 grouped subcarriers as int8, source iwl5300)",
                false, "rt-ac86u", "NAME", cmd);
            TCLAP::ValueArg<int> argAps(
                "", "aps",
                "With --random-room: access points (default 3; those beyond the third are added "
                "to the seed's room, which stays the same)",
                false, 3, "N", cmd);
            TCLAP::ValueArg<std::string> argWriteScenario(
                "", "write-scenario", "With --random-room: also save the room as a scenario file",
                false, "", "FILE.yaml", cmd);
            TCLAP::ValueArg<std::string> argTruth(
                "t", "truth-dir", "Folder for the ground truth (created if needed)", false, "",
                "DIR", cmd);
            TCLAP::ValueArg<std::string> argPcap(
                "", "pcap", "Also write the Nexmon datagrams (one per core and stream) as a pcap",
                false, "", "OUT.pcap", cmd);
            TCLAP::ValueArg<uint32_t> argSeed(
                "s", "seed",
                "Overrides the scenario's seed, the simulated world's (impairments such as the "
                "phase offsets, the drive's and the odometry's noise): rt-ac86u-emulator "
                "--scenario-seed N plays the same world",
                false, 0, "N", cmd);
            TCLAP::ValueArg<double> argDuration(
                "d", "duration", "Overrides the scenario's duration [s]", false, 0, "S", cmd);
            // CSI is noise-like: gzip saves ~7 % and costs ten times the simulation itself.
            // MRPT reads plain and gzipped rawlogs alike.
            TCLAP::ValueArg<int> argCompression(
                "", "compression", "gzip level of the rawlog, 0 (none, default) to 9", false, 0,
                "LEVEL", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress display", cmd);

            if (const int rc = cli::parseCommandLine(cmd, argc, const_cast<const char**>(argv));
                rc >= 0)
                return rc;

            // Everything that can be wrong with the input is found before any file is created.
            const auto& files = argFiles.getValue();
            const size_t wanted = argRandomRoom.isSet() ? 1 : 2;
            if (files.size() != wanted)
                throw std::invalid_argument(
                    argRandomRoom.isSet()
                        ? "with --random-room give only the output rawlog"
                        : "expected SCENARIO.yaml OUT.rawlog (or --random-room SEED OUT.rawlog)");
            if (argWriteScenario.isSet() && !argRandomRoom.isSet())
                throw std::invalid_argument("--write-scenario needs --random-room");
            if (argReceiver.isSet() && !argRandomRoom.isSet())
                throw std::invalid_argument(
                    "--receiver needs --random-room (a scenario file sets receiver.array and "
                    "receiver.csi_format)");
            if (argAps.isSet() && !argRandomRoom.isSet())
                throw std::invalid_argument("--aps needs --random-room");
            if (argAps.getValue() < 3) throw std::invalid_argument("--aps: at least 3");
            if (!sim::isRandomRoomReceiver(argReceiver.getValue()))
                throw std::invalid_argument(
                    "--receiver: unknown receiver '" + argReceiver.getValue() +
                    "' (rt-ac86u or intel5300)");
            const std::string outPath = files.back();
            std::string scenarioName;
            sim::Scenario scenario;
            if (argRandomRoom.isSet())
            {
                if (argRandomRoom.getValue() == 0)
                    throw std::invalid_argument("--random-room: seeds start at 1");
                sim::RandomRoomOptions ro;
                ro.arraysDir = arraysDir();
                ro.receiver = argReceiver.getValue();
                ro.accessPoints = argAps.getValue();
                const std::string yaml = sim::randomRoomYaml(argRandomRoom.getValue(), ro);
                scenario = sim::Scenario::fromYamlText(
                    yaml, "random-room-" + std::to_string(argRandomRoom.getValue()));
                scenarioName = "--random-room " + std::to_string(argRandomRoom.getValue());
                if (argWriteScenario.isSet())
                {
                    std::ofstream f(argWriteScenario.getValue());
                    if (!(f << yaml))
                        throw std::runtime_error(
                            "cannot write '" + argWriteScenario.getValue() + "'");
                }
            }
            else
            {
                scenario = sim::Scenario::fromYamlFile(files.front());
                scenarioName = files.front();
            }
            if (argSeed.isSet()) scenario.seed = argSeed.getValue();
            if (argDuration.isSet())
            {
                if (!(argDuration.getValue() > 0))
                    throw std::invalid_argument("--duration must be > 0");
                scenario.duration_s = argDuration.getValue();
            }
            if (argCompression.getValue() < 0 || argCompression.getValue() > 9)
                throw std::invalid_argument("--compression must be 0..9");
            if (argPcap.isSet() && scenario.receiver.csiFormat != sim::CsiFormat::Nexmon)
                throw std::invalid_argument(
                    std::string("--pcap writes Nexmon datagrams; the receiver reports ") +
                    sim::toString(scenario.receiver.csiFormat) + " CSI (write the rawlog only)");
            sim::Simulator simulator(scenario);

            mrpt::io::CFileGZOutputStream out;
            std::string openError;
            if (!out.open(outPath, argCompression.getValue(), openError))
                throw std::runtime_error("cannot create rawlog '" + outPath + "': " + openError);
            auto archive = mrpt::serialization::archiveFrom(out);
            std::unique_ptr<sim::GroundTruthWriter> truth;
            if (argTruth.isSet())
                truth = std::make_unique<sim::GroundTruthWriter>(argTruth.getValue(), simulator);
            std::unique_ptr<PcapWriter> pcap;
            if (argPcap.isSet()) pcap = std::make_unique<PcapWriter>(argPcap.getValue());

            const auto& sc = simulator.scenario();
            std::vector<uint64_t> framesPerTx(sc.transmitters.size(), 0);
            uint64_t odometryCount = 0, datagrams = 0, events = 0;
            std::vector<uint8_t> datagram;
            cli::Progress progress("wifi-sim", !argQuiet.getValue());
            const auto wallStart = std::chrono::steady_clock::now();
            sim::SimEvent ev;
            double lastTime = 0;
            int rc = 0;
            try
            {
                while (simulator.next(ev))
                {
                    lastTime = ev.time_s;
                    if (ev.kind == sim::SimEvent::Kind::Odometry)
                    {
                        archive << *ev.odometry;
                        ++odometryCount;
                    }
                    else
                    {
                        const CObservationWiFiCSI& obs = *ev.csi;
                        archive << obs;
                        ++framesPerTx[ev.frame.transmitterIndex];
                        if (pcap)
                            for (unsigned m = 0; m < obs.nTx; ++m)
                                for (unsigned i = 0; i < obs.nRx; ++i)
                                {
                                    if (!obs.isPresent(m, i)) continue;
                                    nexmon::encodeDatagram(
                                        nexmon::headerFor(obs, m, i), obs.pair(m, i), datagram);
                                    pcap->writeUdp(datagram.data(), datagram.size(), obs.timestamp);
                                    ++datagrams;
                                }
                    }
                    if (truth) truth->add(ev);
                    if (++events % 1024 == 0)
                    {
                        std::ostringstream detail;
                        detail << std::fixed << std::setprecision(1) << ev.time_s << " / "
                               << sc.duration_s << " s simulated";
                        progress.update(ev.time_s / sc.duration_s, detail.str());
                    }
                }
                progress.done();
                if (truth) truth->finish(sc.duration_s);
            }
            catch (const std::exception& e)
            {
                std::cerr << "\nwifi-sim: error at t = " << lastTime << " s: " << e.what()
                          << "\nwifi-sim: the outputs stop there: the rawlog is valid up to that "
                             "time, the ground truth may be incomplete.\n";
                rc = 1;
            }
            out.close();
            if (pcap) pcap->close();

            const double wall =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count();
            uint64_t frames = 0;
            std::cout << "Scenario : " << sc.name << " (" << scenarioName << "), seed " << sc.seed
                      << ", " << sc.duration_s << " s\n";
            for (size_t i = 0; i < sc.transmitters.size(); ++i)
            {
                const auto& t = sc.transmitters[i];
                std::cout << "  " << std::left << std::setw(14) << t.name << " " << t.mac.asString()
                          << "  " << t.chanspec.asString() << "  " << t.streams << "x"
                          << sc.receiver.array.size() << "  " << framesPerTx[i] << " frames\n";
                frames += framesPerTx[i];
            }
            if (const auto& hops = sc.receiver.channelSchedule; !hops.empty())
            {
                // What the frame counts above mean: each transmitter only while on its channel.
                std::cout << "Receiver : channel schedule";
                for (const auto& c : hops) std::cout << " " << c.asString();
                std::cout << ", " << sc.receiver.channelDwell_s << " s each, "
                          << sc.receiver.channelSwitch_s * 1e3 << " ms to switch\n";
            }
            std::cout << "Trajectory: " << std::setprecision(4)
                      << simulator.trajectory().pathLength_m() << " m driven ("
                      << toString(sc.motion.type) << ")\n"
                      << "Rawlog   : " << outPath << " (" << frames << " CObservationWiFiCSI, "
                      << odometryCount << " CObservationOdometry)\n";
            if (pcap)
                std::cout << "Pcap     : " << argPcap.getValue() << " (" << datagrams
                          << " datagrams)\n";
            if (truth)
                std::cout << "Truth    : " << truth->directory()
                          << "/{trajectory_tum.txt, odometry_tum.txt, transmitters.yaml, "
                             "frames.csv, impairments.json}\n";
            std::cout << "Time     : " << std::setprecision(3) << wall << " s wall clock, "
                      << (wall > 0 ? lastTime / wall : 0.0) << "x real time\n";
            return rc;
        });
}
