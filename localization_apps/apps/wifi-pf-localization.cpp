/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-pf-localization: MRPT's pf-localization (mrpt::apps::MonteCarloLocalization_Rawlog, same
 * .ini) linked with the WiFi bearing map, plus what a user wants around it: bearings from a CSV
 * and odometry from a TUM file instead of a rawlog, localization without odometry (UnknownMotion),
 * input checks with counted warnings, the estimated trajectory as TUM, errors against ground
 * truth, time to converge from the kidnapping, plots. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/apps/MonteCarloLocalization_App.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/obs/CActionRobotMovement3D.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt/system/CTicTac.h>
#include <mrpt/system/datetime.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>  // wifiMapFromIni, boundByInitialPdf
#include <mrpt_wifi/localization/ParticleRecovery.h>
#include <mrpt_wifi/localization/Plot.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/localization/WindowSmoother.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/obs/ConfigKeys.h>
#include <mrpt_wifi/obs/ConfigPaths.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <fstream>
#include <iostream>
#include <optional>

#include "McapOutput.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

namespace
{
std::string fmt(double v, int prec = 3)
{
    char b[64];
    std::snprintf(b, sizeof(b), "%.*f", prec, v);
    return b;
}

/** MRPT's app with a progress line: counts what the data source hands to the filter. */
class ProgressMcl : public mrpt::apps::MonteCarloLocalization_Rawlog
{
public:
    ProgressMcl(double t0, double t1, bool show) : progress_("wifi-pf-localization", show)
    {
        t0_ = t0, t1_ = t1;
    }
    size_t steps = 0;
    void finish() { progress_.done(std::to_string(steps) + " filter steps"); }
    /** No odometry: each step's action is `motion`'s, its constant-velocity prediction fed
     *  with the filter's own estimates (out_estimated_path) as they come. */
    void setUnknownMotion(const UnknownMotion& motion)
    {
        motion_ = motion;
        cv_.emplace(motion);
    }
    /** Re-seeding when the bearings disagree with the estimate (`map` must outlive run()).
     *  With odometry in an observation-only rawlog, this app makes the action/sensory-frame
     *  pairs itself (as MRPT's app does, with `odometryModel`), so the action can carry it. */
    void setRecovery(
        const ParticleRecoveryOptions& options, const CWiFiBearingMap& map,
        const mrpt::obs::CActionRobotMovement2D::TMotionModelOptions& odometryModel)
    {
        recovery_.emplace(options, &map);
        odoModel_ = odometryModel;
    }
    /** With odometry: each step's action is `motion`'s (the app pairs the odometry with the
     *  bearings itself) instead of MRPT's per-step Gaussian. */
    void setOdometryMotion(const OdometryMotion& motion) { odoMotion_ = motion; }
    const std::optional<ParticleRecovery>& recovery() const { return recovery_; }
    /** Reproducible runs. MRPT's app seeds the global generator from the clock just before its
     *  runs; its log line announcing each run (before the particles are drawn) is where the
     *  seed goes in. Must be called before run(). */
    void seedEachRun(unsigned seed)
    {
        setVerbosityLevelForCallbacks(mrpt::system::LVL_INFO);
        logRegisterCallback(
            [this, seed](std::string_view msg, auto, auto, auto)
            {
                if (msg.find("RUNNING FOR") == std::string_view::npos) return;
                mrpt::random::getRandomGenerator().randomize(seed);
                seeded_ = true;
            });
    }

    /** MRPT's app filters in a worker thread, where an exception aborts the whole program: a
     *  failure while preparing a step ends that run (as the end of the input would) and is
     *  thrown here, in the caller's thread, after run(). */
    void rethrowStepFailure() const
    {
        if (stepFailure_) std::rethrow_exception(stepFailure_);
    }

protected:
    bool impl_get_next_observations(
        mrpt::obs::CActionCollection::Ptr& action, mrpt::obs::CSensoryFrame::Ptr& observations,
        mrpt::obs::CObservation::Ptr& observation) override
    {
        if (stepFailure_) return false;  // another run of the same app failed
        try
        {
            const bool ok = nextStep(action, observations, observation);
            // The filter would throw in its thread on a step without a motion it can use.
            if (ok && action && !action->getBestMovementEstimation() &&
                !action->getActionByClass<mrpt::obs::CActionRobotMovement3D>())
                throw std::logic_error(
                    "filter step at t = " + stepTime(observations, observation) +
                    " has no robot motion MRPT's particle filter accepts (" +
                    std::to_string(action->size()) + " actions)");
            return ok;
        }
        catch (...)
        {
            stepFailure_ = std::current_exception();
            return false;
        }
    }

private:
    static std::string stepTime(
        const mrpt::obs::CSensoryFrame::Ptr& observations,
        const mrpt::obs::CObservation::Ptr& observation)
    {
        mrpt::Clock::time_point t = INVALID_TIMESTAMP;
        if (observation)
            t = observation->timestamp;
        else if (observations && !observations->empty())
            t = (*observations->begin())->timestamp;
        return t == INVALID_TIMESTAMP ? std::string("?") : fmt(mrpt::Clock::toDouble(t), 3);
    }

    bool nextStep(
        mrpt::obs::CActionCollection::Ptr& action, mrpt::obs::CSensoryFrame::Ptr& observations,
        mrpt::obs::CObservation::Ptr& observation)
    {
        bool ok = DataSourceRawlog::impl_get_next_observations(action, observations, observation);
        if (recovery_ || odoMotion_) ok = pairWithOdometry(ok, action, observations, observation);
        // Odometry readings only become the next step's action: not a filter step.
        mrpt::Clock::time_point stamp = INVALID_TIMESTAMP;
        if (ok && observation && !IS_CLASS(*observation, mrpt::obs::CObservationOdometry))
            stamp = observation->timestamp;
        else if (ok && observations && !observations->empty())
            stamp = (*observations->begin())->timestamp;
        if (stamp != INVALID_TIMESTAMP && !seeded_ && !warnedUnseeded_)
        {
            std::cerr << "warning: --seed: this MRPT's pf-localization announced no run to seed "
                         "before filtering: this run is not reproducible\n";
            warnedUnseeded_ = true;
        }
        if (stamp != INVALID_TIMESTAMP && t1_ > t0_)
        {
            ++steps;
            const double t = mrpt::Clock::toDouble(stamp);
            progress_.update((t - t0_) / (t1_ - t0_), std::to_string(steps) + " steps");
        }
        if ((cv_ || recovery_) && ok && action && stamp != INVALID_TIMESTAMP)
            adjustAction(action, observations, stamp);
        return ok;
    }

    // Observation-only rawlog with odometry: the readings are consumed here and the next
    // bearing comes as an action/sensory-frame pair, the action the odometry increment through
    // the same Gaussian model MRPT's app uses ([DummyOdometryParams]).
    bool pairWithOdometry(
        bool ok, mrpt::obs::CActionCollection::Ptr& action,
        mrpt::obs::CSensoryFrame::Ptr& observations, mrpt::obs::CObservation::Ptr& observation)
    {
        while (ok && observation && IS_CLASS(*observation, mrpt::obs::CObservationOdometry))
        {
            const auto& odo = static_cast<const mrpt::obs::CObservationOdometry&>(*observation);
            // The first reading, or a new run of the filter (time going backwards).
            if (!lastOdo_ || odo.timestamp < lastOdoStamp_) odoAtLastStep_ = odo.odometry;
            lastOdo_ = odo.odometry, lastOdoStamp_ = odo.timestamp;
            ok = DataSourceRawlog::impl_get_next_observations(action, observations, observation);
        }
        if (!ok || !observation || !lastOdo_) return ok;
        observations = mrpt::obs::CSensoryFrame::Create();
        observations->insert(observation);
        const mrpt::poses::CPose2D increment = *lastOdo_ - *odoAtLastStep_;
        mrpt::obs::CActionRobotMovement2D act;
        if (odoMotion_)
        {
            const bool first =
                odoStepStamp_ == INVALID_TIMESTAMP || observation->timestamp < odoStepStamp_;
            const double dt =
                first ? 0.0 : mrpt::system::timeDifference(odoStepStamp_, observation->timestamp);
            act = *odoMotion_->makeAction(dt, increment);
        }
        else
            act.computeFromOdometry(increment, odoModel_);
        act.timestamp = odoStepStamp_ = observation->timestamp;
        odoAtLastStep_ = lastOdo_;
        action = mrpt::obs::CActionCollection::Create();
        action->insert(act);
        observation.reset();
        return ok;
    }

    // Without odometry: the rawlog's zero-mean action replaced by the unknown-motion model's,
    // centred on the constant-velocity prediction from the estimates of the steps before this
    // one. With recovery: a share of the particles re-seeded while the bearings disagree with
    // the estimate.
    void adjustAction(
        mrpt::obs::CActionCollection::Ptr& action, const mrpt::obs::CSensoryFrame::Ptr& sf,
        mrpt::Clock::time_point stamp)
    {
        const double t = mrpt::Clock::toDouble(stamp);
        // A new run of the filter (several particle counts or repetitions) starts over.
        const bool restart = lastStamp_ == INVALID_TIMESTAMP || stamp < lastStamp_;
        if (restart)
        {
            if (cv_) cv_->reset();
            if (recovery_) recovery_->reset();
        }
        else if (const auto it = out_estimated_path.find(lastStamp_);
                 it != out_estimated_path.end())
        {
            const mrpt::math::TPose2D est(it->second.x, it->second.y, it->second.yaw);
            if (cv_) cv_->addEstimate(mrpt::Clock::toDouble(lastStamp_), est);
            if (recovery_) recovery_->setEstimate(est);
        }
        const double dt = restart ? 0.0 : t - mrpt::Clock::toDouble(lastStamp_);
        lastStamp_ = stamp;
        double reseed = 0;
        if (recovery_)
        {
            if (sf)
                for (const auto& o : *sf)
                    if (const auto* b = dynamic_cast<const CObservationWiFiBearing*>(o.get()))
                        recovery_->checkBearing(mrpt::Clock::toDouble(b->timestamp), *b);
            reseed = recovery_->reseedFraction(t, dt);
        }
        if (!cv_ && reseed <= 0) return;
        const auto best = action->getBestMovementEstimation();
        if (!cv_ && !best) return;
        mrpt::obs::CActionRobotMovement2D a =
            cv_ ? *motion_.makeAction(dt, cv_->predictIncrement(t)) : *best;
        if (reseed > 0) a = withReseeding(a, reseed, recovery_->reseedRadius_m());
        a.timestamp = stamp;
        action = mrpt::obs::CActionCollection::Create();
        action->insert(a);
    }

    cli::Progress progress_;
    std::exception_ptr stepFailure_;
    bool seeded_ = false, warnedUnseeded_ = false;
    double t0_ = 0, t1_ = 0;
    UnknownMotion motion_;
    std::optional<ConstantVelocityPrediction> cv_;
    std::optional<ParticleRecovery> recovery_;
    std::optional<OdometryMotion> odoMotion_;
    mrpt::Clock::time_point odoStepStamp_ = INVALID_TIMESTAMP;
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions odoModel_;
    std::optional<mrpt::poses::CPose2D> lastOdo_, odoAtLastStep_;
    mrpt::Clock::time_point lastOdoStamp_ = INVALID_TIMESTAMP;
    mrpt::Clock::time_point lastStamp_ = INVALID_TIMESTAMP;
};

}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "wifi-pf-localization",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Global (kidnapped-robot) localization with MRPT's particle filter and the WiFi "
                "bearing map. Takes the same .ini as pf-localization (see "
                "share/localization/pf-localization-wifi.ini) and a rawlog of bearing (+ "
                "odometry) observations, or a bearings CSV (+ odometry TUM file). Without "
                "odometry the robot's motion is an unknown-motion random walk bounded by "
                "--max-speed (the .ini's [UnknownMotion] section).",
                ' ', "0.1");
            TCLAP::UnlabeledValueArg<std::string> argIni(
                "config", "pf-localization .ini", true, "", "CONFIG.ini", cmd);
            TCLAP::UnlabeledValueArg<std::string> argRawlog(
                "rawlog", "Rawlog with CObservationWiFiBearing + CObservationOdometry", false, "",
                "IN.rawlog", cmd);
            TCLAP::ValueArg<std::string> argCsv(
                "b", "bearings-csv", "Bearings CSV (instead of a rawlog)", false, "", "B.csv", cmd);
            TCLAP::ValueArg<std::string> argOdo(
                "", "odometry-tum",
                "Odometry as a TUM file (with --bearings-csv). Optional: without it the motion "
                "is unknown (see --max-speed)",
                false, "", "ODO.txt", cmd);
            TCLAP::ValueArg<double> argMaxSpeed(
                "", "max-speed",
                "Without odometry: the robot's top speed [m/s]. Between filter steps dt apart "
                "the pose takes a Gaussian step of sigma = max_speed*sqrt(dt*tau) per axis "
                "around the constant-velocity prediction (tau: correlation_time_s, or "
                "wide_correlation_time_s for a wide_fraction of the steps), so over tau the walk "
                "spreads as far as the robot can drive. Overrides [UnknownMotion] max_speed_mps "
                "of the .ini (default 0.5)",
                false, 0.5, "M/S", cmd);
            TCLAP::ValueArg<std::string> argPose(
                "", "sensor-pose",
                "Receive array on the robot for CSV bearings: x y z yaw pitch roll (m, deg)", false,
                "0 0 0 0 0 0", "x y z yaw pitch roll", cmd);
            TCLAP::ValueArg<std::string> argGt(
                "g", "ground-truth-tum", "True robot trajectory (TUM) for errors and plots", false,
                "", "GT.txt", cmd);
            TCLAP::ValueArg<std::string> argOut(
                "o", "out-dir", "Output folder", false, "wifi-pf-out", "DIR", cmd);
            TCLAP::ValueArg<std::string> argMap(
                "m", "map", "Transmitters YAML (overrides transmitters_file of the .ini)", false,
                "", "TX.yaml", cmd);
            TCLAP::ValueArg<int> argParticles(
                "n", "particles", "Overrides particles_count of the .ini", false, 0, "N", cmd);
            TCLAP::ValueArg<double> argThr(
                "", "converged-threshold", "Error [m] below which the filter counts as converged",
                false, 1.0, "M", cmd);
            TCLAP::ValueArg<double> argHold(
                "", "converged-hold", "... and must stay for this long [s]", false, 5.0, "S", cmd);
            TCLAP::ValueArg<double> argSkip(
                "", "skip",
                "Drop the first S seconds of bearings: the filter starts (uniformly, lost) there, "
                "as if the robot had been kidnapped to wherever it is at that time. Times to "
                "converge and errors.csv count from this kidnapping moment",
                false, 0.0, "S", cmd);
            TCLAP::ValueArg<unsigned> argSeed(
                "", "seed",
                "Seed of the particle filter's random numbers: the same input, .ini and seed "
                "give the same run",
                false, 1, "N", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress display", cmd);
            TCLAP::SwitchArg argNoPlots("", "no-plots", "Don't draw PNGs", cmd);
            TCLAP::ValueArg<std::string> argMcap(
                "", "mcap", mcap_output::optionHelp(), false, "", "OUT.mcap", cmd);

            cli::JoinedArgv args(argc, argv, "--sensor-pose", 6);
            if (const int rc = cli::parseCommandLine(cmd, args.argc(), args.argv()); rc >= 0)
                return rc;

            const std::string outDir = argOut.getValue();
            mrpt::system::createDirectory(outDir);
            if (!mrpt::system::directoryExists(outDir))
                throw std::runtime_error("cannot create " + outDir);

            // ---- The map, exactly as the filter will build it from the .ini. A relative
            // transmitters_file that isn't there from the working directory is taken relative
            // to the .ini (pf-localization itself only looks in the working directory).
            mrpt::config::CConfigFileMemory ini;
            ini.setContent(mrpt::io::file_get_contents(argIni.getValue()));
            // A misspelt section name would leave its keys unread without a word.
            for (const auto& w : config::unreadSections(ini, config::pfLocalizationMrptSections()))
                std::cerr << "wifi-pf-localization: warning: " << argIni.getValue() << ": " << w
                          << "\n";
            const std::string mapSect = "MetricMap_wifiBearingMap_00_creationOpts";
            std::string txFile = ini.read_string(mapSect, "transmitters_file", "");
            if (argMap.isSet())
                txFile = argMap.getValue();  // a command-line path: from the working directory
            else if (!txFile.empty())
            {
                // From the .ini's folder, else the working directory, else the data folder.
                const auto r = config::resolveConfigPath(
                    txFile, config::iniDirectoryOf(argIni.getValue()), "localization",
                    argIni.getValue() + ": [" + mapSect + "] transmitters_file");
                if (!r.note.empty()) std::cerr << "note: " << r.note << "\n";
                txFile = r.path;
            }
            if (!txFile.empty()) ini.write(mapSect, "transmitters_file", txFile);
            CWiFiBearingMap::Ptr wifiMap;
            try
            {
                wifiMap =
                    wifiMapFromIni(ini, mrpt::system::extractFileDirectory(argIni.getValue()));
            }
            catch (const std::exception& e)
            {
                throw std::runtime_error(argIni.getValue() + ": " + e.what());
            }
            const auto& txs = wifiMap->transmitters();
            // The robot can't leave the building: without an area of its own the map is bounded
            // by the init_PDF box (where the kidnapped robot may be); both given and disagreeing
            // is most likely a half-edited .ini, said before anything runs.
            std::string areaWarning;
            const bool areaFromInitPdf = boundByInitialPdf(*wifiMap, ini, &areaWarning);
            if (!areaWarning.empty())
                std::cerr << "wifi-pf-localization: warning: " << argIni.getValue() << ": "
                          << areaWarning << "\n";

            // ---- The input.
            std::string rawlog = argRawlog.getValue();
            std::vector<BearingRecord> bearings;
            Trajectory2D odo;
            InputWarnings warn;
            size_t otherObs = 0;
            if (argCsv.isSet())
            {
                if (!rawlog.empty())
                    throw std::invalid_argument("give a rawlog or --bearings-csv, not both");
                BearingCsvOptions co;
                const auto sp = cli::poseFromText(argPose.getValue(), "--sensor-pose");
                co.sensorPose = mrpt::math::TPose2D(sp.x(), sp.y(), sp.yaw());
                co.names = &txs;
                bearings = readBearingCsv(argCsv.getValue(), co, &warn);
                std::cerr << warn.csvWarning(argCsv.getValue());
                if (argOdo.isSet()) odo = Trajectory2D::fromTumFile(argOdo.getValue());
            }
            else
            {
                if (rawlog.empty()) throw std::invalid_argument("give a rawlog or --bearings-csv");
                if (argOdo.isSet())
                    throw std::invalid_argument(
                        "--odometry-tum goes with --bearings-csv (a rawlog carries its odometry)");
                auto c = readRawlog(rawlog);
                bearings = std::move(c.bearings);
                odo = std::move(c.odometry);
                otherObs = c.otherObservations;
                if (otherObs)
                    std::cerr << "note: " << otherObs
                              << " other observations (CSI, ...) in the rawlog are left out of "
                                 "the filter's input (each would be a step without "
                                 "information)\n";
            }
            if (bearings.empty()) throw std::runtime_error("the input holds no bearings");
            // E.g. AoA-only bearings on a map set to AoD only: the filter would run to the end
            // and report its initial distribution.
            {
                const auto& lo = wifiMap->likelihoodOptions;
                if (std::none_of(
                        bearings.begin(), bearings.end(),
                        [&](const BearingRecord& b) { return recordWeighed(b, lo.model, lo.use); }))
                    throw std::invalid_argument(
                        argIni.getValue() + ": none of the " + std::to_string(bearings.size()) +
                        " bearings of the input has an angle the map weighs (" +
                        weighedAnglesString(lo.model, lo.use) + ")");
            }
            // Without odometry: the unknown-motion random walk, from the .ini's [UnknownMotion]
            // section, --max-speed overriding.
            UnknownMotion motion;
            if (odo.empty())
            {
                motion.loadFromConfigFile(ini, "UnknownMotion");
                if (argMaxSpeed.isSet()) motion.maxSpeed_mps = argMaxSpeed.getValue();
                motion.validate();
                std::cerr << "note: no odometry: the motion model is the unknown-motion "
                          << motion.asString() << "\n";
            }
            // With odometry: the .ini's [OdometryMotion] if it has one, else MRPT's model.
            std::optional<OdometryMotion> odometryMotion;
            if (!odo.empty() && ini.sectionExists("OdometryMotion"))
            {
                odometryMotion.emplace();
                odometryMotion->loadFromConfigFile(ini, "OdometryMotion");
            }
            ParticleRecoveryOptions recoveryOptions;
            recoveryOptions.loadFromConfigFile(ini, "ParticleRecovery");
            WindowSmootherOptions smootherOptions;
            smootherOptions.loadFromConfigFile(ini, "WindowSmoother");
            smootherOptions.track.forwardOnly = motion.forwardOnly;  // without odometry
            smootherOptions.graph.useAoa = wifiMap->likelihoodOptions.use.aoa;
            smootherOptions.graph.useAod = wifiMap->likelihoodOptions.use.aod;
            smootherOptions.graph.useAoaAlternatives =
                wifiMap->likelihoodOptions.model.aoaAlternativeShare > 0;
            if (recoveryOptions.rate_hz > 0 && !wifiMap->area())
                std::cerr << "warning: [ParticleRecovery] needs the map's area (min_x ... max_y "
                             "in its creationOpts, or an init_PDF box): off\n";
            std::vector<BearingRecord> usable;
            // The kidnapping moment: the filter starts lost (uniform particles) here.
            const double tSkip = std::min_element(
                                     bearings.begin(), bearings.end(),
                                     [](const auto& a, const auto& b) { return a.t < b.t; })
                                     ->t +
                                 argSkip.getValue();
            for (const auto& b : bearings)
            {
                if (b.t < tSkip) continue;
                if (!txs.find(b.transmitter))
                {
                    warn.unknownTransmitter++;
                    continue;
                }
                if (!odo.empty() && (b.t < odo.t.front() || b.t > odo.t.back()))
                {
                    warn.outsideTrajectory++;
                    continue;
                }
                usable.push_back(b);
            }
            if (usable.empty())
                throw std::runtime_error(
                    "no usable bearings: " + warn.summary() +
                    " (check the map's MACs and that odometry and bearings overlap in time)");
            if (odo.empty())
            {
                // Action/sensory-frame rawlog: each step's action is the random walk over dt.
                rawlog = outDir + "/input.rawlog";
                writePfRawlogUnknownMotion(rawlog, usable, motion);
            }
            else if (argCsv.isSet() || warn.total() || otherObs || argSkip.getValue() > 0)
            {
                // The filter reads a rawlog: write the checked input as one.
                rawlog = outDir + "/input.rawlog";
                Trajectory2D odoUsed;  // odometry from the first used bearing on
                for (size_t i = 0; i < odo.size(); ++i)
                    if (i + 1 >= odo.size() || odo.t[i + 1] >= usable.front().t)
                        odoUsed.push_back(odo.t[i], odo.poses[i]);
                writePfRawlog(rawlog, usable, odoUsed);
            }

            // ---- Run MRPT's Monte Carlo localization app.
            const double t0 = usable.front().t, t1 = usable.back().t;
            ProgressMcl app(t0, t1, !argQuiet.getValue());
            app.setMinLoggingLevel(mrpt::system::LVL_WARN);
            app.allow_quit_on_esc_key = false;
            app.fill_out_estimated_path = true;
            if (odo.empty()) app.setUnknownMotion(motion);
            if (recoveryOptions.rate_hz > 0)
                app.setRecovery(recoveryOptions, *wifiMap, odometryMotionModel(ini));
            if (odometryMotion) app.setOdometryMotion(*odometryMotion);
            {
                const std::string iniPath = argIni.getValue();
                const char* a[] = {"wifi-pf-localization", iniPath.c_str(), rawlog.c_str()};
                app.initialize(3, a);
            }
            const auto sect = mrpt::apps::MonteCarloLocalization_Base::sect;
            if (argParticles.isSet())
                app.params.write(sect, "particles_count", argParticles.getValue());
            app.params.write(sect, "logOutput_dir", outDir + "/mrpt");
            if (!txFile.empty()) app.params.write(mapSect, "transmitters_file", txFile);
            if (const double motionWeight =
                    motionBearingWeight(!odo.empty(), motion, odometryMotion);
                motionWeight != 1)
                app.params.write(
                    "MetricMap_wifiBearingMap_00_likelihoodOpts", "bearing_weight",
                    wifiMap->likelihoodOptions.bearingWeight * motionWeight);
            // The filter's own map gets the same area (from the init_PDF box, or widened to it).
            if (wifiMap->area())
            {
                const auto& a = *wifiMap->area();
                app.params.write(mapSect, "min_x", a.min.x);
                app.params.write(mapSect, "max_x", a.max.x);
                app.params.write(mapSect, "min_y", a.min.y);
                app.params.write(mapSect, "max_y", a.max.y);
            }
            const auto counts = app.params.read_string(sect, "particles_count", "", true);
            app.seedEachRun(argSeed.getValue());
            mrpt::system::CTicTac timer;
            app.run();
            const double runTime = timer.Tac();
            app.rethrowStepFailure();
            app.finish();

            Trajectory2D est;
            for (const auto& [t, p] : app.out_estimated_path)
                est.push_back(mrpt::Clock::toDouble(t), mrpt::math::TPose2D(p.x, p.y, p.yaw));
            // The window smoother refines the filter's estimates causally: each from the
            // odometry and bearings up to its own time. The filter's spread is not kept by
            // MRPT's loop: the smoother's residual test alone decides (offline).
            WindowSmoother smoother(smootherOptions, txs);
            smoother.setArea(wifiMap->area());
            size_t refined = 0;
            if (smootherOptions.enabled)
            {
                est.saveTum(
                    outDir + "/pf_estimate_tum.txt", "wifi-pf-localization particle filter mean");
                auto inTime = usable;
                std::stable_sort(
                    inTime.begin(), inTime.end(),
                    [](const auto& a, const auto& b) { return a.t < b.t; });
                size_t io = 0, ib = 0;
                for (size_t i = 0; i < est.size(); ++i)
                {
                    const double t = est.t[i];
                    for (; io < odo.size() && odo.t[io] <= t; ++io)
                        smoother.addOdometry(odo.t[io], odo.poses[io]);
                    for (; ib < inTime.size() && inTime[ib].t <= t; ++ib)
                        smoother.addBearing(inTime[ib]);
                    if (const auto p = smoother.update(t, est.poses[i], [] { return 0.0; }))
                        est.poses[i] = *p, ++refined;
                }
            }
            est.saveTum(
                outDir + "/estimate_tum.txt",
                smootherOptions.enabled
                    ? "wifi-pf-localization estimate (PF mean refined by the window smoother)"
                    : "wifi-pf-localization estimate (PF mean)");
            // MRPT's loop keeps no particle spread: poses without covariance.
            if (argMcap.isSet() && est.size() > 0)
                mcap_output::writeTrajectory(
                    argMcap.getValue(), est, nullptr, usable, &txs, nullptr);

            std::ostringstream sum;
            sum << "wifi-pf-localization summary\n"
                << "  input          : " << usable.size() << " bearings of " << txs.size()
                << " known transmitters, "
                << (odo.empty() ? "no odometry (" + motion.asString() + ")"
                                : std::to_string(odo.size()) + " odometry readings (" +
                                      (odometryMotion ? odometryMotion->asString()
                                                      : "MRPT's model, [DummyOdometryParams]") +
                                      ")")
                << "\n"
                << "  warnings       : " << warn.summary() << "\n"
                << "  sharp bearings : "
                << sharpCoverage(
                       usable, wifiMap->likelihoodOptions.use,
                       mrpt::DEG2RAD(recoveryOptions.maxStd_deg))
                       .asString()
                << " (sigma <= " << recoveryOptions.maxStd_deg
                << " deg, [ParticleRecovery] max_std_deg; without odometry a pose needs 3)\n"
                << "  particles      : " << counts << "\n"
                << "  filter steps   : " << app.steps << " in " << fmt(runTime, 2) << " s ("
                << fmt(app.steps / std::max(runTime, 1e-9), 1) << " steps/s)\n"
                << "  map warnings   : " << wifiMap->unknownTransmitterCount() << "\n";
            if (const auto area = areaSummary(*wifiMap, est.poses); !area.empty())
                sum << "  area           : " << area
                    << (areaFromInitPdf        ? " (the init_PDF box)"
                        : !areaWarning.empty() ? " (the map's; see the warning above)"
                                               : " (the map's)")
                    << "\n";
            sum << "  window smoother: " << smootherOptions.asString();
            if (smootherOptions.enabled)
                sum << ": " << refined << " of " << est.size() << " estimates refined, "
                    << smoother.accepted() << " of " << smoother.solves() << " solves used ("
                    << smoother.restarts() << " restarts: newest bearings unexplained), "
                    << fmt(smoother.solveTime_s(), 2) << " s";
            sum << "\n";
            sum << "  recovery       : " << recoveryOptions.asString();
            if (const auto& r = app.recovery(); r) sum << ": " << recoverySummary(*r);
            sum << "\n";
            if (argGt.isSet())
            {
                const auto gt = Trajectory2D::fromTumFile(argGt.getValue());
                std::vector<double> times, errs;
                for (size_t i = 0; i < est.size(); ++i)
                {
                    mrpt::math::TPose2D g;
                    if (!gt.interpolate(est.t[i], g, 0.5)) continue;
                    times.push_back(est.t[i] - tSkip);
                    errs.push_back(std::hypot(est.poses[i].x - g.x, est.poses[i].y - g.y));
                }
                if (errs.empty())
                    throw std::runtime_error("the ground truth doesn't overlap the estimate");
                // Time to converge, from the kidnapping moment t_k (the start of the input after
                // --skip, when the filter is started lost with particles spread uniformly):
                // t_c - t_k, where t_c is the time of the first estimate from which the error
                // stays below the threshold for `hold` seconds (the whole window must lie inside
                // the run). Each estimate is the PF mean after that step's bearings, so a filter
                // that converges on its first step reports ~0 s: the summary adds the number of
                // filter steps and the first estimate's error to tell those apart.
                double tc = -1;
                size_t stepsToConverge = 0;
                for (size_t i = 0; i < errs.size() && tc < 0; ++i)
                {
                    size_t j = i;
                    while (j < errs.size() && errs[j] < argThr.getValue() &&
                           times[j] - times[i] < argHold.getValue())
                        ++j;
                    if (j < errs.size() && errs[j] < argThr.getValue())
                        tc = times[i], stepsToConverge = i + 1;
                }
                std::vector<double> after;
                for (size_t i = 0; i < errs.size(); ++i)
                    if (tc >= 0 && times[i] >= tc) after.push_back(errs[i]);
                const auto all = computeStats(errs), conv = computeStats(after);
                {
                    std::ofstream f(outDir + "/errors.csv");
                    f << "# t_s: seconds since the kidnapping moment (filter start, UNIX "
                      << fmt(tSkip, 3) << ")\n";
                    f << "t_s,position_error_m\n";
                    for (size_t i = 0; i < errs.size(); ++i)
                        f << times[i] << "," << errs[i] << "\n";
                }
                sum << "  error (all)    : " << all.asString() << "\n";
                if (tc >= 0)
                    sum << "  converged after: " << fmt(tc, 3) << " s from the kidnapping ("
                        << stepsToConverge << " filter steps; error < " << argThr.getValue()
                        << " m for " << argHold.getValue() << " s; first estimate's error "
                        << fmt(errs.front(), 2) << " m)\n"
                        << "  after converged: " << conv.asString() << "\n"
                        << "  target         : median after convergence <= 0.5 m (WiROS 1.2 m): "
                        << (conv.median <= 0.5 ? "MET" : "NOT MET") << "\n";
                else
                    sum << "  converged after: never (error never stayed < " << argThr.getValue()
                        << " m for " << argHold.getValue() << " s)\n";

                if (!argNoPlots.getValue())
                {
                    std::string err;
                    plot::Figure traj;
                    traj.title = "wifi-pf-localization: estimate vs ground truth";
                    traj.xlabel = "x [m]", traj.ylabel = "y [m]", traj.equalAxes = true;
                    plot::Series g{"ground truth", {}, {}, "lines lw 2 lc rgb '#333333'"};
                    for (const auto& p : gt.poses) g.x.push_back(p.x), g.y.push_back(p.y);
                    plot::Series e{"PF mean", {}, {}, "lines lw 1 lc rgb '#d62728'"};
                    for (const auto& p : est.poses) e.x.push_back(p.x), e.y.push_back(p.y);
                    plot::Series a{"access points", {}, {}, "points pt 5 ps 2 lc rgb '#1f77b4'"};
                    for (const auto& t : txs.transmitters())
                        a.x.push_back(t.pose.x), a.y.push_back(t.pose.y);
                    traj.series = {g, e, a};
                    if (!plot::savePng(traj, outDir + "/trajectory.png", &err))
                        std::cerr << "warning: " << err << "\n";
                    plot::Figure et;
                    et.title = "Position error over time";
                    et.xlabel = "time [s]", et.ylabel = "error [m]";
                    et.series = {{"PF mean error", times, errs, "lines lw 1"}};
                    if (tc >= 0)
                        et.extra.push_back(
                            "set arrow from " + fmt(tc) + ", graph 0 to " + fmt(tc) +
                            ", graph 1 nohead dt 2 lc rgb 'black'\nset label 'converged' at " +
                            fmt(tc) + ", graph 0.95 offset 0.5,0");
                    et.extra.push_back("set logscale y");
                    plot::savePng(et, outDir + "/error_time.png", &err);
                    plot::Figure cdf;
                    cdf.title = "Position error CDF after convergence";
                    cdf.xlabel = "error [m]", cdf.ylabel = "fraction";
                    cdf.series = {plot::cdf(after.empty() ? errs : after, "wifi-pf-localization")};
                    cdf.extra.push_back(
                        "set xrange [0:1.4<*]\nset arrow from 1.2, graph 0 to 1.2, graph 1 nohead "
                        "dt 2\n"
                        "set label 'WiROS median 1.2 m' at 1.2, graph 0.5 offset 0.5,0");
                    plot::savePng(cdf, outDir + "/error_cdf.png", &err);
                }
            }
            std::cout << sum.str();
            std::ofstream(outDir + "/summary.txt") << sum.str();
            return 0;
        });
}
