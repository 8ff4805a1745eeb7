/* mrpt_wifi — WiFi channel state information for MRPT.  */
/** live-replay: wifi-localize's filter (LiveLocalizer) fed a bearings CSV without the clock, a
 *  fixed number of bearings per step, from a chosen moment of the drive. A live run steps on
 *  whatever the clock has queued and starts when the program is up; this gives the same filter
 *  the same input every time, so what changes a run (the start, the steps, the seed) can be told
 *  apart. A development command (share/localization/README.md, "Live and offline without
 *  odometry: where the run starts"); `scripts/pf_rooms.py --live-steps N` runs it on a sweep's
 *  rooms. Without odometry only: the bearings are all the filter gets. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/core/Clock.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/obs/CommandLine.h>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <stdexcept>

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

int main(int argc, char** argv)
{
    return cli::runMain(
        "live-replay",
        [&]
        {
            TCLAP::CmdLine cmd(
                "wifi-localize's filter (LiveLocalizer) on a bearings CSV, without the clock: "
                "N bearings queued at a time, in steps of the .ini's max_bearings_per_step, from "
                "--skip seconds into the drive, the same run for the same input, .ini and seed. "
                "Without odometry. Writes estimate_tum.txt (the reported pose) and "
                "pf_estimate_tum.txt (the particles' mean) to the output folder, one line per "
                "step.",
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argIni(
                "config", "wifi-localize .ini (its localization sections are read)", true, "",
                "CONFIG.ini", cmd);
            TCLAP::ValueArg<std::string> argCsv(
                "b", "bearings-csv", "Bearings CSV (csi-bearings --csv)", true, "", "B.csv", cmd);
            TCLAP::ValueArg<std::string> argOut(
                "o", "out-dir", "Output folder", true, "", "DIR", cmd);
            TCLAP::ValueArg<std::string> argPose(
                "", "sensor-pose",
                "Receive array on the robot: x y z yaw pitch roll [m, deg], as "
                "wifi-pf-localization --sensor-pose",
                false, "0 0 0 0 0 0", "X Y Z YAW PITCH ROLL", cmd);
            TCLAP::ValueArg<std::string> argMap(
                "m", "map", "Transmitters YAML (overrides transmitters_file of the .ini)", false,
                "", "TX.yaml", cmd);
            TCLAP::ValueArg<unsigned> argParticles(
                "n", "particles", "Overrides particles_count of the .ini", false, 0, "N", cmd);
            TCLAP::ValueArg<unsigned> argPerStep(
                "", "bearings-per-step",
                "Bearings queued at a time (1: one step per bearing, as wifi-pf-localization; a "
                "live run gets what the clock queued, often 1-3 and up to tens after a smoother "
                "solve); the .ini's [wifi-localize] max_bearings_per_step splits them into "
                "steps, as in wifi-localize (0: one step)",
                false, 1, "N", cmd);
            TCLAP::ValueArg<double> argSkip(
                "", "skip",
                "Drop the first S seconds of bearings, as wifi-pf-localization --skip: the filter "
                "starts there, as a live run that came up late",
                false, 0.0, "S", cmd);
            TCLAP::ValueArg<unsigned> argSeed(
                "", "seed", "Seed of the particle filter's random numbers", false, 1, "N", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress display", cmd);

            cli::JoinedArgv args(argc, argv, "--sensor-pose", 6);
            if (const int rc = cli::parseCommandLine(cmd, args.argc(), args.argv()); rc >= 0)
                return rc;
            if (argPerStep.getValue() == 0)
                throw std::invalid_argument("--bearings-per-step must be >= 1");
            if (!(argSkip.getValue() >= 0)) throw std::invalid_argument("--skip must be >= 0");

            const std::string iniPath = argIni.getValue();
            if (!mrpt::system::fileExists(iniPath))
                throw std::runtime_error("'" + iniPath + "': no such file");
            mrpt::config::CConfigFileMemory ini;
            ini.setContent(mrpt::io::file_get_contents(iniPath));
            if (argMap.isSet())
                ini.write(
                    "MetricMap_wifiBearingMap_00_creationOpts", "transmitters_file",
                    argMap.getValue());
            if (argParticles.getValue() > 0)
                ini.write(
                    "LocalizationExperiment", "particles_count", int(argParticles.getValue()));
            BearingCsvOptions co;
            const auto sp = cli::poseFromText(argPose.getValue(), "--sensor-pose");
            co.sensorPose = mrpt::math::TPose2D(sp.x(), sp.y(), sp.yaw());
            InputWarnings warn;
            auto bearings = readBearingCsv(argCsv.getValue(), co, &warn);
            std::cerr << warn.csvWarning(argCsv.getValue());
            std::stable_sort(
                bearings.begin(), bearings.end(),
                [](const BearingRecord& a, const BearingRecord& b) { return a.t < b.t; });
            if (bearings.empty())
                throw std::runtime_error("'" + argCsv.getValue() + "': no bearings");
            const double t0 = bearings.front().t + argSkip.getValue();
            bearings.erase(
                bearings.begin(), std::find_if(
                                      bearings.begin(), bearings.end(),
                                      [&](const BearingRecord& b) { return b.t >= t0; }));

            const std::string outDir = argOut.getValue();
            mrpt::system::createDirectory(outDir);
            std::ofstream tum(outDir + "/estimate_tum.txt"), pfTum(outDir + "/pf_estimate_tum.txt");
            if (!tum || !pfTum) throw std::runtime_error("cannot write to '" + outDir + "'");

            // Before the filter draws its first particles, as wifi-localize --seed.
            mrpt::random::getRandomGenerator().randomize(argSeed.getValue());
            LiveLocalizer loc(ini, mrpt::system::extractFileDirectory(iniPath));
            cli::Progress progress("live-replay", !argQuiet.getValue());
            double lastOutput = -1e300;
            for (size_t i = 0; i < bearings.size(); ++i)
            {
                loc.addBearing(observationFromRecord(bearings[i]));
                if (loc.pendingBearings() < argPerStep.getValue() && i + 1 < bearings.size())
                    continue;
                // The queue drained as wifi-localize drains it: steps of the .ini's
                // max_bearings_per_step (0: all at once).
                while (loc.step())
                {
                    // As wifi-localize: a step whose newest bearing is not newer gives no line.
                    const double t = loc.lastStepTime();
                    if (!(t > lastOutput)) continue;
                    lastOutput = t;
                    tum << Trajectory2D::tumLine(t, loc.estimate());
                    pfTum << Trajectory2D::tumLine(t, loc.mean());
                }
                progress.update(double(i + 1) / double(bearings.size()));
            }
            progress.done();
            std::cout << "live-replay: " << loc.bearingsUsed() << " bearings from "
                      << argSkip.getValue()
                      << " s (unknown transmitter: " << loc.unknownTransmitter() << "), "
                      << loc.steps() << " filter steps, queued " << argPerStep.getValue()
                      << " at a time, " << loc.particles().size() << " particles, seed "
                      << argSeed.getValue() << ": " << outDir << "/estimate_tum.txt\n";
            return 0;
        });
}
