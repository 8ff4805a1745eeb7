/* bearing-accuracy: median / 90th-percentile AoA error of every estimator against the
 * simulator's ground truth, at 10/20/30 dB, LoS-only / moderate / strong multipath, calibrated
 * with the simulator's true offsets and uncalibrated; the Cramér–Rao bound beside it; AoD on the
 * kidnapped scenario. Prints Markdown tables.
 *
 *   bearing-accuracy [--estimates N] [--quick]
 *   bearing-accuracy --rooms N [--development] [--receiver rt-ac86u|intel5300] ...
 *     the random-room tables (windows sampled over each room's drive, each estimated alone)
 *   bearing-accuracy --rooms N --stream [--poses truth|odometry|drifting|none] ...
 *     whole streams: each room's odometry and CSI in time order through BearingProcessor, as
 *     csi-bearings runs them, so per-transmitter tracking sees the stream
 *   bearing-accuracy --truth-calibration SCENARIO.yaml DIR [--seed N]
 *     writes the simulator's true receiver offsets of every channel of the scenario as
 *     calibration files DIR/<device>/ch<C>_<BW>mhz.yaml (reference files for demos and for
 *     checking a calibration tool). The offsets are drawn from the seed: a recording made with
 *     `wifi-sim -s N` needs the same `--seed N` (the scenario's own seed otherwise). */
#include <cstring>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "BearingAccuracy.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::test;

namespace
{
/** The random-room tables: every estimator, LoS-only and moderate multipath, 10–30 dB. */
int roomTables(
    unsigned rooms, bool evaluation, unsigned estimatesPerRoom, const std::vector<double>& snrs,
    const std::vector<std::string>& algos, const std::string& params, unsigned windowFrames,
    const std::string& receiver)
{
    const auto seeds = roomSeeds(evaluation, rooms);
    std::cout << std::fixed << std::setprecision(2);
    std::cout << "# AoA accuracy over " << rooms << " random rooms ("
              << (evaluation ? "evaluation" : "development") << " seeds " << seeds.front() << "–"
              << seeds.back() << "), " << estimatesPerRoom << " estimates per room, "
              << windowFrames << "-frame windows, receiver " << receiver
              << ", true receiver offsets, true poses\n\n"
              << "Error to the nearer reported mirror candidate; 'central': truth within 75° of "
                 "broadside. Coverage: share of errors within 2σ / 3σ of the reported σ. CRB: "
                 "median one-path Cramér–Rao bound.\n\n";
    for (Environment env : {Environment::LineOfSight, Environment::Moderate})
    {
        std::cout << "## " << toString(env) << "\n\n"
                  << "| estimator | SNR [dB] | median (central) | p90 (central) | >30° (central) "
                     "| >30° (all) | median (all) | ≤2σ | ≤3σ | median σ (central / all) | CRB |\n"
                     "|---|---|---|---|---|---|---|---|---|---|---|\n";
        for (double snr : snrs)
        {
            std::vector<AccuracyDataset> data;
            for (uint32_t seed : seeds)
            {
                AccuracyCase c;
                c.environment = env;
                c.snr_dB = snr;
                c.estimates = estimatesPerRoom;
                c.windowFrames = windowFrames;
                data.push_back(makeRandomRoomDataset(c, seed, receiver));
            }
            for (const auto& n : algos)
            {
                std::vector<ErrorRecord> recs;
                for (const auto& d : data)
                    collectErrors(d, n, recs, mrpt::containers::yaml::FromText(params));
                const RoomStats s = summarize(recs);
                std::cout << "| " << n << " | " << std::setprecision(0) << snr
                          << std::setprecision(2) << " | " << s.centralMedian_deg << " | "
                          << s.centralP90_deg << " | " << std::setprecision(1)
                          << 100 * s.centralBeyond30 << " % | " << 100 * s.beyond30 << " % | "
                          << std::setprecision(2) << s.median_deg << " | " << std::setprecision(1)
                          << 100 * s.withinTwoSigma << " % | " << 100 * s.withinThreeSigma
                          << " % | " << std::setprecision(2) << s.centralMedianStd_deg << " / "
                          << s.medianStd_deg << " | " << std::setprecision(3) << s.crbMedian_deg
                          << " |\n"
                          << std::flush;
            }
        }
        std::cout << "\n";
    }
    return 0;
}
/** The weighed candidate directions of a record as one CSV cell:
 *  "error_deg:weight:relative_power:delay_after_ns:kept;..." (delay "nan" without). */
std::string candidatesCell(const ErrorRecord& r)
{
    std::ostringstream o;
    o << std::setprecision(4);
    for (size_t i = 0; i < r.candidates.size(); ++i)
    {
        const auto& c = r.candidates[i];
        o << (i ? ";" : "") << c.error_deg << ":" << c.weight << ":" << c.relativePower << ":"
          << c.delayAfter_ns << ":" << int(c.kept);
    }
    return o.str();
}

/** Whole-stream tables: every room's odometry and CSI in time order through BearingProcessor
 *  (so per-transmitter tracking sees the stream), moderate multipath. */
int streamTables(
    unsigned rooms, bool evaluation, const std::vector<double>& snrs,
    const std::vector<std::string>& algos, const std::string& params, StreamCase c,
    const std::string& dumpFile)
{
    const auto seeds = roomSeeds(evaluation, rooms);
    std::ofstream dump;
    if (!dumpFile.empty())
    {
        dump.open(dumpFile);
        if (!dump) throw std::runtime_error("cannot write '" + dumpFile + "'");
        dump << "seed,algo,snr_db,time_s,tx,truth_deg,estimate_deg,error_deg,std_deg,central,"
                "track_choice,track_support,yaw_deg,quality,alt_error_deg,candidates\n";
    }
    std::cout << std::fixed << std::setprecision(2);
    std::cout << "# AoA accuracy over whole streams: " << rooms << " random rooms ("
              << (evaluation ? "evaluation" : "development") << " seeds " << seeds.front() << "–"
              << seeds.back() << "), first " << c.duration_s << " s of each, one estimate per "
              << "transmitter every " << c.stride << " frames, " << toString(c.poses)
              << ", tracking "
              << (c.tracking ? (*c.tracking ? "on" : "off") : "default (on for `default`)") << ", "
              << toString(c.base.environment) << ", true receiver offsets";
    if (c.jumpRate_Hz > 0)
        std::cout << ", jump states on (3 states 3 ns apart, each with its own phase, switching "
                  << "at " << c.jumpRate_Hz << " Hz; the calibration holds every state)";
    std::cout << "\n\n"
              << "| estimator | SNR [dB] | median (central) | p90 (central) | >30° (central) "
                 "| >30° (all) | median (all) | ≤2σ | ≤3σ | median σ (central / all) | CRB | "
                 "estimates |\n"
                 "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (double snr : snrs)
    {
        c.base.snr_dB = snr;
        std::map<std::string, std::vector<ErrorRecord>> recs;
        for (uint32_t seed : seeds)
        {
            std::map<std::string, std::vector<ErrorRecord>> room;
            streamErrors(c, seed, algos, mrpt::containers::yaml::FromText(params), room);
            std::cerr << "." << std::flush;
            for (auto& [a, v] : room)
            {
                for (const auto& r : v)
                    if (dump)
                        dump << seed << "," << a << "," << snr << "," << r.time_s << ","
                             << r.transmitter << "," << r.truth_deg << "," << r.estimate_deg << ","
                             << r.error_deg << "," << r.std_deg << "," << r.central << ","
                             << r.trackChoice << "," << r.trackSupport << "," << r.yaw_deg << ","
                             << r.quality << "," << r.alternativeError_deg << ","
                             << candidatesCell(r) << "\n";
                recs[a].insert(recs[a].end(), v.begin(), v.end());
            }
        }
        std::cerr << "\n";
        for (const auto& n : algos)
        {
            const RoomStats s = summarize(recs[n]);
            std::cout << "| " << n << " | " << std::setprecision(0) << snr << std::setprecision(2)
                      << " | " << s.centralMedian_deg << " | " << s.centralP90_deg << " | "
                      << std::setprecision(1) << 100 * s.centralBeyond30 << " % | "
                      << 100 * s.beyond30 << " % | " << std::setprecision(2) << s.median_deg
                      << " | " << std::setprecision(1) << 100 * s.withinTwoSigma << " % | "
                      << 100 * s.withinThreeSigma << " % | " << std::setprecision(2)
                      << s.centralMedianStd_deg << " / " << s.medianStd_deg << " | "
                      << std::setprecision(3) << s.crbMedian_deg << " | " << s.count << " |\n"
                      << std::flush;
        }
    }
    std::cout << "\n";
    return 0;
}
}  // namespace

int main(int argc, char** argv)
{
    unsigned estimates = 200;
    bool quick = false;
    if (argc >= 2 && !std::strcmp(argv[1], "--truth-calibration"))
    {
        const bool withSeed = argc == 6 && !std::strcmp(argv[4], "--seed");
        if (argc != 4 && !withSeed)
        {
            std::cerr << "usage: bearing-accuracy --truth-calibration SCENARIO.yaml DIR [--seed "
                         "N]\n  (--seed: the seed given to wifi-sim -s; the receiver's phase "
                         "offsets are drawn from it)\n";
            return 1;
        }
        sim::Scenario sc = sim::Scenario::fromYamlFile(argv[2]);
        if (withSeed)
        {
            char* end = nullptr;
            const unsigned long seed = std::strtoul(argv[5], &end, 10);
            if (end == argv[5] || *end != '\0')
            {
                std::cerr << "bearing-accuracy: --seed '" << argv[5] << "' is not a number\n";
                return 1;
            }
            sc.seed = uint32_t(seed);
        }
        sim::Simulator simulator(sc);
        const AntennaArray rx = fromSimArray(sc.receiver.array);
        for (const auto& t : sc.transmitters)
        {
            const PhaseCalibration cal = truthCalibration(simulator, rx, t.chanspec);
            const std::string path = PhaseCalibration::pathFor(argv[3], rx.name, t.chanspec);
            cal.saveYamlFile(path);
            std::cout << "wrote " << path << " (seed " << sc.seed << ")\n";
        }
        return 0;
    }
    unsigned rooms = 0;
    bool development = false;
    std::vector<double> snrs = {10, 20, 25, 30};
    std::vector<std::string> algos;
    std::string params = "{}";
    unsigned windowFrames = 8;
    std::string receiver = "rt-ac86u";
    bool stream = false;
    StreamCase sc;
    std::string dumpFile;
    for (int i = 1; i < argc; ++i)
    {
        if (!std::strcmp(argv[i], "--stream"))
        {
            stream = true;
            continue;
        }
        if (!std::strcmp(argv[i], "--poses") && i + 1 < argc)
        {
            const std::string p = argv[++i];
            if (p == "truth")
                sc.poses = StreamPoses::Truth;
            else if (p == "odometry")
                sc.poses = StreamPoses::Odometry;
            else if (p == "drifting")
                sc.poses = StreamPoses::DriftingOdometry;
            else if (p == "none")
                sc.poses = StreamPoses::None;
            else
            {
                std::cerr << "--poses: truth, odometry, drifting or none, not '" << p << "'\n";
                return 1;
            }
            continue;
        }
        if (!std::strcmp(argv[i], "--tracking") && i + 1 < argc)
        {
            const std::string t = argv[++i];
            if (t != "on" && t != "off")
            {
                std::cerr << "--tracking: on or off, not '" << t << "'\n";
                return 1;
            }
            sc.tracking = t == "on";
            continue;
        }
        if (!std::strcmp(argv[i], "--duration") && i + 1 < argc)
        {
            sc.duration_s = std::atof(argv[++i]);
            continue;
        }
        if (!std::strcmp(argv[i], "--stride") && i + 1 < argc)
        {
            sc.stride = unsigned(std::max(1, std::atoi(argv[++i])));
            continue;
        }
        if (!std::strcmp(argv[i], "--jumps") && i + 1 < argc)
        {
            sc.jumpRate_Hz = std::atof(argv[++i]);
            if (!(sc.jumpRate_Hz >= 0))
            {
                std::cerr << "--jumps: a switching rate in Hz (0: off)\n";
                return 1;
            }
            continue;
        }
        if (!std::strcmp(argv[i], "--los"))
        {
            sc.base.environment = Environment::LineOfSight;
            continue;
        }
        if (!std::strcmp(argv[i], "--dump") && i + 1 < argc)
        {
            dumpFile = argv[++i];
            continue;
        }
        if (!std::strcmp(argv[i], "--estimates") && i + 1 < argc)
            estimates = unsigned(std::atoi(argv[++i]));
        else if (!std::strcmp(argv[i], "--quick"))
            quick = true;
        else if (!std::strcmp(argv[i], "--rooms") && i + 1 < argc)
            rooms = unsigned(std::atoi(argv[++i]));
        else if (!std::strcmp(argv[i], "--development"))
            development = true;
        else if (!std::strcmp(argv[i], "--snr") && i + 1 < argc)
            snrs = {std::atof(argv[++i])};
        else if (!std::strcmp(argv[i], "--algo") && i + 1 < argc)
            algos.push_back(argv[++i]);
        else if (!std::strcmp(argv[i], "--params") && i + 1 < argc)
            params = argv[++i];
        else if (!std::strcmp(argv[i], "--window-frames") && i + 1 < argc)
            windowFrames = unsigned(std::atoi(argv[++i]));
        else if (
            !std::strcmp(argv[i], "--receiver") && i + 1 < argc &&
            sim::isRandomRoomReceiver(argv[i + 1]))
            receiver = argv[++i];
        else
        {
            std::cerr
                << "usage: bearing-accuracy [--estimates N] [--quick]\n"
                   "       bearing-accuracy --rooms N [--development] [--estimates "
                   "PER_ROOM] [--snr DB] [--algo NAME]... [--params YAML] [--window-frames N]\n"
                   "         [--receiver rt-ac86u|intel5300]\n"
                   "       bearing-accuracy --rooms N --stream [--development] [--snr DB] "
                   "[--algo NAME]... [--params YAML] [--poses truth|odometry|drifting|none] "
                   "[--tracking on|off] [--duration S] [--stride N] [--los] [--jumps HZ] "
                   "[--dump CSV]\n";
            return 1;
        }
    }
    if (rooms > 0 && stream)
    {
        if (receiver != "rt-ac86u")
        {
            std::cerr << "--receiver: the stream tables simulate the RT-AC86U only\n";
            return 1;
        }
        if (algos.empty()) algos = {"default", "fft"};
        if (snrs.size() == 4) snrs = {10, 25, 30};
        return streamTables(rooms, !development, snrs, algos, params, sc, dumpFile);
    }
    if (rooms > 0)
    {
        if (algos.empty())
            for (const auto& n : bearing::arrayEstimatorNames())
                if (n != "aod") algos.push_back(n);
        return roomTables(
            rooms, !development, estimates, snrs, algos, params, windowFrames, receiver);
    }
    const auto names = bearing::arrayEstimatorNames();
    std::cout << std::fixed << std::setprecision(2);
    std::cout
        << "# AoA accuracy, scenario `bearing` (3 APs, rt-ac86u linear array, 80 MHz), "
        << estimates << " estimates per cell\n\n"
        << "Error = |estimate − truth| to the nearer of the two reported mirror candidates "
           "(linear array). CRB: median over the estimates of the one-path Cramér–Rao bound "
           "for the frames and streams used; err/CRB: RMS of error ÷ CRB, over all "
           "estimates and within ±60° of broadside (beyond, the 26 mm spacing, just over λ/2, "
           "aliases one endfire onto the other).\n\n";
    for (bool calibrated : {true, false})
    {
        if (quick && !calibrated) continue;
        for (Environment env :
             {Environment::LineOfSight, Environment::Moderate, Environment::Strong})
        {
            std::cout << "## " << (calibrated ? "calibrated" : "uncalibrated") << ", "
                      << toString(env) << "\n\n";
            std::cout << "| estimator | SNR [dB] | median [deg] | p90 [deg] | CRB [deg] | err/CRB "
                         "| err/CRB ±60° | mean reported σ [deg] | err ≤ 3σ | mean quality |\n"
                         "|---|---|---|---|---|---|---|---|---|---|\n";
            for (double snr : {10.0, 20.0, 30.0})
            {
                if (quick && snr != 20.0) continue;
                AccuracyCase c;
                c.scenarioFile = scenarioPath("bearing");
                c.environment = env;
                c.snr_dB = snr;
                c.calibrated = calibrated;
                c.estimates = estimates;
                const AccuracyDataset d = makeDataset(c);
                for (const auto& n : names)
                {
                    if (n == "aod") continue;  // AoA part identical to aoa_only
                    const AccuracyStats s = evaluate(d, n);
                    std::cout << "| " << n << " | " << snr << " | " << s.median_deg << " | "
                              << s.p90_deg << " | " << std::setprecision(3) << s.crbMedian_deg
                              << " | " << std::setprecision(1) << s.errorOverCrbRms << " | "
                              << s.errorOverCrbRmsCentral << " | " << std::setprecision(2)
                              << s.meanStd_deg << " | " << s.withinThreeSigma << " | "
                              << s.meanQuality << " |\n";
                }
            }
            std::cout << "\n";
        }
    }

    std::cout << "# AoD accuracy, scenario `kidnapped` (4 APs with ap-linear-4, 4 streams)\n\n"
              << "| estimator | environment | SNR [dB] | AoD median [deg] | AoD p90 [deg] | AoA "
                 "median [deg] | AoA p90 [deg] |\n"
                 "|---|---|---|---|---|---|---|\n";
    for (Environment env : {Environment::LineOfSight, Environment::Moderate})
        for (double snr : {10.0, 20.0, 30.0})
        {
            if (quick && snr != 20.0) continue;
            AccuracyCase c;
            c.scenarioFile = scenarioPath("kidnapped");
            c.environment = env;
            c.snr_dB = snr;
            c.estimates = estimates;
            const AccuracyDataset d = makeDataset(c);
            for (const char* method : {"bartlett", "music"})
            {
                const AccuracyStats s = evaluate(
                    d, "aod",
                    mrpt::containers::yaml::FromText(
                        std::string("aod_method: ") + method + "\nwindow: 4"));
                std::cout << "| aod (" << method << ", window 4) | " << toString(env) << " | "
                          << snr << " | " << s.aodMedian_deg << " | " << s.aodP90_deg << " | "
                          << s.median_deg << " | " << s.p90_deg << " |\n";
            }
        }
    return 0;
}
