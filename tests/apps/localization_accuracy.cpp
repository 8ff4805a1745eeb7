/* localization-accuracy: the three localization case studies over many random rooms, each room
 * judged on its own (issue 19.3), as bearing-accuracy --rooms does for the bearings.
 *
 *   localization-accuracy --rooms N [--eval] [--first-seed S] [--work DIR] [--no-live]
 *                         [--aps N] [--live-chain app|sensor] ...
 *
 * Per room (sim::randomRoomYaml, with odometry errors drawn from a realistic range):
 *  - bearings through the real chain: wifi-sim → csi-bearings (`default`, the receiver
 *    calibrated with the simulator's true offsets, odometry from the rawlog; for the runs
 *    without odometry also with it ignored, --no-odometry);
 *  - kidnapped robot on a random drive: wifi-pf-localization (offline) and wifi-localize (live,
 *    the room streamed in real time by rt-ac86u-emulator), each with and without odometry;
 *  - drift correction on a multi-lap loop: wifi-graphslam --aps (known) and --estimate-aps;
 *  - device mapping on the same loop from odometry: wifi-iot-map --odometry-tum (the APs are
 *    the devices);
 *  - the share of the room's bearings beyond 30° (truth within 75° of broadside).
 * Prints progress per room, a per-room table, the share of rooms meeting each target, the worst
 * rooms with what makes them fail, writes WORK/rooms.csv and pictures of the failing rooms. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/DeviceMapper.h>
#include <mrpt_wifi/localization/Plot.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/localization/WindowSmoother.h>
#include <mrpt_wifi/obs/CommandLine.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <future>
#include <iomanip>
#include <iostream>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "BearingAccuracy.h"
#include "EmulatorProcess.h"
#include "SshdFixture.h"  // freeLoopbackPort
#include "TrackFromTruth.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;
namespace fs = std::filesystem;

namespace
{
const std::string kShare = std::string(MRPT_WIFI_SOURCE_DIR) + "/share";
const std::string kSensorPose = "--sensor-pose 0.1 0 0.4 0 0 0";  // the random rooms' receiver
const mrpt::math::TPose2D kSensorPose2D(0.1, 0, 0);               // the same, in the plane

struct Options
{
    fs::path work;
    int accessPoints = 3;  //!< sim::RandomRoomOptions::accessPoints
    double kidnappedDuration_s = 40;
    unsigned laps = 3;
    int particles = 3000;
    /** Filter seeds of each offline kidnapped run: a room's figure is the run with the median
     *  error (one run's luck moved a room's figure up to 3×: evaluation room 1138 with
     *  odometry, seeds 1–5, 0.08–0.24 m). */
    int offlineSeeds = 3;
    /** The same for the live runs (wifi-localize --seed): a live run is one draw too, of the
     *  seed and of how the clock batched the bearings (evaluation room 1140 without odometry
     *  never converged in one sweep and came within 0.06 m and 0.04 m in two reruns). */
    int liveSeeds = 3;
    bool live = true;
    /** Who computes the live bearings: wifi-localize's own chain ("app") or the CSI sensor's
     *  (`bearing_*` keys in its section, "sensor"); the same estimator, calibration and arrays. */
    std::string liveChain = "app";
    int apStreams = 0;  //!< sim::RandomRoomOptions::accessPointStreams (0: drawn, 2 or 4)
    /** AoD too: the APs' transmit chains calibrated as a user would (calibrateTransmitChains)
     *  and used by every estimator (needs apStreams 2 or 4). */
    bool aod = false;
    double convergedThreshold_m = 1.0, convergedHold_s = 5.0;  // the apps' defaults
};

/** Kidnapped-robot figures of one run: errors of the estimate against the truth, times from
 *  the first estimate (the kidnapping moment: the filter starts with uniform particles). */
struct KidnappedFigures
{
    bool ran = false, converged = false;
    double timeToConverge_s = NAN;
    double medianAfter_m = NAN;  //!< median error after convergence (of all if it never did)
    double worstAfter_m = NAN;   //!< maximum error after convergence (of all if it never did)
    double worstAll_m = NAN;     //!< maximum error over the whole run
    size_t estimates = 0;
    /** Share of the estimates after convergence whose error lies inside the filter's own 95 %
     *  ellipse (live runs: wifi-localize's estimate_cov.csv; NaN without it). */
    double inside95After = NAN;
    /** The same within 3σ: Mahalanobis distance ≤ 3 (98.9 % of a Gaussian's errors). */
    double inside3SigmaAfter = NAN;
    /** The first estimate's time after the drive's start [s]: the first bearing's, unless the
     *  run missed the start of the drive (a live run that came up after the stream began). */
    double start_s = NAN;
    Trajectory2D estimate;  //!< on the truth's clock
};

/** A run's median error after convergence; ∞ when it never converged, NaN when it did not run. */
double kidnappedMedian(const KidnappedFigures& k)
{
    return k.ran ? (k.converged ? k.medianAfter_m : INFINITY) : NAN;
}

/** The run with the median error (the lower middle of an even count), never-converged runs
 *  last; `runs` is not empty. */
KidnappedFigures medianRun(std::vector<KidnappedFigures> runs)
{
    const auto middle = runs.begin() + std::ptrdiff_t(runs.size() - 1) / 2;
    std::nth_element(
        runs.begin(), middle, runs.end(),
        [](const KidnappedFigures& a, const KidnappedFigures& b)
        { return kidnappedMedian(a) < kidnappedMedian(b); });
    return std::move(*middle);
}

/** Position covariances (xx, xy, yy) [m²] of wifi-localize's estimate_cov.csv, one per row;
 *  empty when the file is missing or malformed. */
std::vector<std::array<double, 3>> readEstimateCovariances(const fs::path& csv)
{
    std::vector<std::array<double, 3>> out;
    std::ifstream f(csv);
    std::string line;
    if (!std::getline(f, line)) return {};  // header
    while (std::getline(f, line))
    {
        std::vector<double> v;
        std::stringstream ss(line);
        for (std::string cell; std::getline(ss, cell, ',');) v.push_back(std::atof(cell.c_str()));
        if (v.size() < 8) return {};  // the reported σ first (then the particles' alone)
        const double sx = v[4], sy = v[5], rho = v[6];
        out.push_back({sx * sx, rho * sx * sy, sy * sy});
    }
    return out;
}

/** The number captured by `pattern`'s first group in a program's summary.txt; NaN without the
 *  file or a match. */
double numberInSummary(const fs::path& summary, const std::string& pattern)
{
    std::smatch m;
    const std::string text = fs::exists(summary) ? test::readFile(summary.string()) : "";
    return std::regex_search(text, m, std::regex(pattern)) ? std::stod(m[1]) : NAN;
}

/** The 99th percentile of the lag in wifi-localize's summary.txt ("lag [ms] : p50 …, p99 …")
 *  [ms]; NaN without it. */
double liveLagP99_ms(const fs::path& summary)
{
    return numberInSummary(summary, R"(lag \[ms\]\s*: p50 [0-9.]+, p99 ([0-9.]+))");
}

/** The share of seconds with 3+ transmitters sharp in wifi-pf-localization's summary.txt
 *  ("sharp bearings : 3+ transmitters with a sharp bearing in N % of …"); NaN without it. */
double sharp3Share(const fs::path& summary)
{
    return numberInSummary(
               summary,
               R"(sharp bearings : 3\+ transmitters with a sharp bearing in ([0-9.]+) %)") /
           100;
}

KidnappedFigures kidnappedFigures(
    const Trajectory2D& est, const Trajectory2D& truth, const Options& o,
    const std::vector<std::array<double, 3>>& covariances = {})
{
    KidnappedFigures k;
    std::vector<double> times, errs;
    // Per error: inside the 95 % ellipse, within 3σ (with covariances only).
    std::vector<bool> inside, within3Sigma;
    const bool withCov = covariances.size() == est.size();
    for (size_t i = 0; i < est.size(); ++i)
    {
        mrpt::math::TPose2D g;
        if (!truth.interpolate(est.t[i], g, 0.5)) continue;
        times.push_back(est.t[i] - est.t.front());
        const double ex = est.poses[i].x - g.x, ey = est.poses[i].y - g.y;
        errs.push_back(std::hypot(ex, ey));
        if (withCov)
        {
            const auto& c = covariances[i];
            const double m2 = mahalanobis2(c[0], c[1], c[2], ex, ey);
            inside.push_back(m2 <= kChi2TwoDof95);
            within3Sigma.push_back(m2 <= 9);
        }
    }
    k.estimate = est;
    k.estimates = errs.size();
    if (!est.empty() && !truth.empty()) k.start_s = est.t.front() - truth.t.front();
    if (errs.empty()) return k;
    k.ran = true;
    // Converged at the first estimate from which the error stays below the threshold for the
    // hold time (as wifi-pf-localization and wifi-localize report it).
    size_t first = errs.size();
    for (size_t i = 0, run = 0; i < errs.size(); ++i)
    {
        if (errs[i] >= o.convergedThreshold_m)
        {
            run = i + 1;
            continue;
        }
        if (times[i] - times[run] >= o.convergedHold_s)
        {
            first = run;
            break;
        }
    }
    k.converged = first < errs.size();
    const std::vector<double> after(errs.begin() + long(k.converged ? first : 0), errs.end());
    k.timeToConverge_s = k.converged ? times[first] : NAN;
    k.medianAfter_m = computeStats(after).median;
    k.worstAfter_m = computeStats(after).max;
    k.worstAll_m = computeStats(errs).max;
    if (withCov && k.converged)
    {
        const auto shareAfter = [first](const std::vector<bool>& v) {
            return double(std::count(v.begin() + long(first), v.end(), true)) /
                   double(v.size() - first);
        };
        k.inside95After = shareAfter(inside);
        k.inside3SigmaAfter = shareAfter(within3Sigma);
    }
    return k;
}

struct DriftFigures
{
    bool ran = false;
    double odometryAte_m = NAN, slamAte_m = NAN;  //!< median ATE (rigid alignment, evo)
    double reduction = NAN;                       //!< 1 − slam / odometry
    /** The same with both aligned by a similarity (evo's --correct_scale): with estimated APs
     *  nothing observes the scale, which stays the odometry's; this is what the bearings fixed. */
    double scaleFreeReduction = NAN;
    Trajectory2D aligned;  //!< the solution in the truth's frame
};

struct DeviceFigures
{
    bool ran = false;
    size_t devices = 0, localized = 0, inside = 0;
    double medianError_m = NAN, maxError_m = NAN;
    double insideShare = NAN;
    std::vector<std::array<double, 5>> estimates;  //!< x, y, cov_xx, cov_xy, cov_yy
    std::vector<std::string> weak;                 //!< devices with a "weak geometry" note
};

struct BearingFigures
{
    size_t count = 0, central = 0;
    double centralBeyond30 = NAN, beyond30 = NAN, centralMedian_deg = NAN;
    /** Of the central bearings, those beyond 30° and beyond 3 of their own σ: the outliers the
     *  estimator did not flag, which mislead a consumer that weighs bearings by their σ. */
    double centralBeyond30Unflagged = NAN;
    /** Of the central bearings, those beyond 30° from the reported direction and from every
     *  alternative direction it carries (issue 53's "beyond their alternatives"). */
    double centralBeyond30AndAlternatives = NAN;
    double centralWithin3Sigma = NAN;  //!< error ≤ 3 reported σ
    double alternativesPerBearing = NAN;

    static BearingFigures of(const std::vector<test::ErrorRecord>& errors)
    {
        const auto s = test::summarize(errors);
        BearingFigures f{
            s.count, s.centralCount, s.centralBeyond30, s.beyond30, s.centralMedian_deg};
        if (s.centralCount)
            f.centralBeyond30Unflagged =
                double(std::count_if(
                    errors.begin(), errors.end(),
                    [](const auto& e)
                    { return e.central && e.error_deg > 30 && e.error_deg > 3 * e.std_deg; })) /
                double(s.centralCount);
        if (s.centralCount)
        {
            size_t beyond = 0, within = 0, alternatives = 0;
            for (const auto& e : errors)
            {
                if (!e.central) continue;
                beyond +=
                    e.error_deg > 30 && !(e.alternativeError_deg <= 30);  // NaN: no alternative
                within += e.error_deg <= 3 * e.std_deg;
                alternatives += e.candidates.size();
            }
            const double n = double(s.centralCount);
            f.centralBeyond30AndAlternatives = double(beyond) / n;
            f.centralWithin3Sigma = double(within) / n;
            f.alternativesPerBearing = double(alternatives) / n;
        }
        return f;
    }
};

struct Room
{
    uint32_t seed = 0;
    double width = 0, depth = 0, speed = 0;
    double scaleError = 0, yawScaleError = 0, yawDrift_deg_per_m = 0;
    double apMinSeparation_m = NAN, apTriangle = NAN;  //!< AP geometry
    std::vector<mrpt::math::TPoint2D> aps;
    Trajectory2D kidnappedTruth, loopTruth, loopOdometry;
    // kidnapped: [offline, live] × [odometry, none]
    KidnappedFigures kidnapped[2][2];
    DriftFigures drift[2];  // known APs, estimated APs
    DeviceFigures devices;
    BearingFigures bearings;            //!< both drives
    BearingFigures bearingsOfDrive[2];  //!< the kidnapped (random) drive, the loop
    /** Without odometry, the window smoother's track fitted from the true poses of the
     *  kidnapped drive: median error of its newest node (trackFromTruthOfRoom). */
    double noOdoTrackFromTruth_m = NAN;
    double noOdoTrackFromTruthFull_m = NAN;  //!< the same over full windows only
    /** Share of the kidnapped drive's seconds in which 3 or more APs gave a sharp bearing
     *  without odometry (wifi-pf-localization's "sharp bearings"): a pose fixed by the bearings
     *  alone needs 3. */
    double noOdoSharp3Share = NAN;
    /** Offline kidnapped runs, [odometry?]: each filter seed's median error after convergence
     *  (∞: never converged); kidnapped[0][odo] is the median one's figures. */
    std::array<std::vector<double>, 2> offlineRuns_m;
    /** The same of the live runs, [odometry?], kidnapped[1][odo] being the median one's; and
     *  each live run's 99th percentile of the lag (pose output − newest bearing in it) [ms]:
     *  a run far behind real time measured the machine's load, not the filter. */
    std::array<std::vector<double>, 2> liveRuns_m, liveLagP99_ms;
    std::vector<std::string> errors;  //!< programs that failed
    double wall_s = 0;
};

const char* kRunNames[2][2] = {
    {"offline, odometry", "offline, no odometry"}, {"live, odometry", "live, no odometry"}};

/** A program that failed: named in the room's errors, printed with its command and the end
 *  of its output. */
void reportFailure(
    Room& room, const std::string& what, const std::string& problem, const std::string& cmd,
    const std::string& output)
{
    room.errors.push_back(what);
    std::cerr << "\n[localization-accuracy] room " << room.seed << ": " << what << " " << problem
              << ":\n  " << cmd << "\n"
              << output.substr(output.size() > 2000 ? output.size() - 2000 : 0) << "\n";
}

/** Runs a program of the build; a failure goes to reportFailure(), the room goes on. */
test::CommandResult runOrThrow(const std::string& cmd, Room& room, const std::string& what)
{
    auto r = test::run(cmd);
    if (r.exitCode != 0)
        reportFailure(
            room, what, "failed (exit " + std::to_string(r.exitCode) + ")", cmd, r.output);
    return r;
}

std::string bin(const std::string& program)
{
    return test::binDir() + "/" + program;
}

/** An .ini from a shipped one: every section and key copied, `set` ("SECTION/key" → value)
 *  written over it, sections in `drop` left out. */
void deriveIni(
    const std::string& from, const std::map<std::string, std::string>& set,
    const std::set<std::string>& drop, const std::string& to)
{
    const mrpt::config::CConfigFileMemory in(test::readFile(from));
    mrpt::config::CConfigFileMemory out;
    std::vector<std::string> sections, keys;
    in.getAllSections(sections);
    for (const auto& s : sections)
    {
        if (drop.count(s)) continue;
        in.getAllKeys(s, keys);
        for (const auto& k : keys) out.write(s, k, in.read_string(s, k, ""));
    }
    for (const auto& [sk, v] : set)
    {
        const auto slash = sk.find('/');
        if (!drop.count(sk.substr(0, slash)))
            out.write(sk.substr(0, slash), sk.substr(slash + 1), v);
    }
    std::ofstream(to) << out.getContent();
}

std::string fmt(double v, int digits = 2)
{
    if (std::isinf(v)) return "never";  // a kidnapped run that never converged
    if (!std::isfinite(v)) return "–";
    std::ostringstream o;
    o << std::fixed << std::setprecision(digits) << v;
    return o.str();
}

/** The cells of one CSV line (quotes are not parsed: the columns read here come before any
 *  quoted cell, and a quoted cell here holds no comma). */
std::vector<std::string> csvCells(const std::string& line)
{
    std::vector<std::string> c;
    std::istringstream s(line);
    for (std::string x; std::getline(s, x, ',');) c.push_back(x);
    return c;
}

/** Index of the column `name` in a CSV header line; throws naming the file when it is missing. */
size_t csvColumn(
    const std::vector<std::string>& header, const std::string& name, const std::string& file)
{
    const auto it = std::find(header.begin(), header.end(), name);
    if (it == header.end()) throw std::runtime_error(file + ": no column " + name);
    return size_t(it - header.begin());
}

/** AoA truth of every frame (mac, time rounded to 0.1 ms) from wifi-sim's frames.csv. */
std::map<std::pair<std::string, long long>, double> frameTruth(const std::string& framesCsv)
{
    std::map<std::pair<std::string, long long>, double> truth;
    std::ifstream f(framesCsv);
    std::string line;
    std::getline(f, line);
    const auto header = csvCells(line);
    const size_t cT = csvColumn(header, "timestamp_unix", framesCsv),
                 cMac = csvColumn(header, "mac", framesCsv),
                 cAoa = csvColumn(header, "aoa_rad", framesCsv);
    while (std::getline(f, line))
    {
        const auto c = csvCells(line);
        if (c.size() <= std::max({cT, cMac, cAoa})) continue;
        truth[{c[cMac], std::llround(std::stod(c[cT]) * 1e4)}] = std::stod(c[cAoa]);
    }
    return truth;
}

/** Bearing errors of a csi-bearings CSV against the truth of its drive (nearer mirror
 *  candidate, as bearing-accuracy counts them); appends to the room's pool. */
void addBearingErrors(
    const std::string& csv, const std::string& framesCsv, const AntennaArray& rx,
    std::vector<test::ErrorRecord>& out)
{
    const auto truth = frameTruth(framesCsv);
    BearingCsvOptions bo;
    for (const auto& b : readBearingCsv(csv, bo))
    {
        if (!b.hasAoa) continue;
        const auto it = truth.find({b.transmitter.asString(), std::llround(b.t * 1e4)});
        if (it == truth.end()) continue;
        double err = angleDistance(b.aoa, it->second);
        if (b.aoaAmbiguous) err = std::min(err, angleDistance(b.aoaMirror, it->second));
        test::ErrorRecord r;
        // The nearest alternative direction (its mirror too); `candidates` counts them.
        for (const auto& a : b.aoaAlternatives())
        {
            double e = angleDistance(a.aoa, it->second);
            if (b.aoaAmbiguous) e = std::min(e, angleDistance(aoaMirrorOf(b, a.aoa), it->second));
            e *= 180 / M_PI;
            r.alternativeError_deg =
                std::isnan(r.alternativeError_deg) ? e : std::min(r.alternativeError_deg, e);
            r.candidates.push_back({e, a.weight, NAN, NAN, true});
        }
        r.error_deg = err * 180 / M_PI;
        r.std_deg = b.aoaStd * 180 / M_PI;
        r.central = std::min(
                        angleDistance(it->second, rx.broadside()),
                        angleDistance(rx.mirrorOf(it->second), rx.broadside())) <= 75 * M_PI / 180;
        out.push_back(r);
    }
}

/** The AP layout's geometry: the smallest distance between two APs and, of the triangles of
 *  three APs, the largest area over that of an equilateral one on the triangle's longest side
 *  (0 = all collinear). */
void apGeometry(Room& room)
{
    double minSep = 1e9;
    const auto& a = room.aps;
    for (size_t i = 0; i < a.size(); ++i)
        for (size_t j = i + 1; j < a.size(); ++j) minSep = std::min(minSep, (a[i] - a[j]).norm());
    room.apMinSeparation_m = minSep;
    room.apTriangle = 0;
    for (size_t i = 0; i < a.size(); ++i)
        for (size_t j = i + 1; j < a.size(); ++j)
            for (size_t k = j + 1; k < a.size(); ++k)
            {
                const double longest =
                    std::max({(a[i] - a[j]).norm(), (a[j] - a[k]).norm(), (a[k] - a[i]).norm()});
                if (longest <= 0) continue;
                const double area = 0.5 * std::abs(
                                              (a[j].x - a[i].x) * (a[k].y - a[i].y) -
                                              (a[k].x - a[i].x) * (a[j].y - a[i].y));
                room.apTriangle =
                    std::max(room.apTriangle, area / (std::sqrt(3.0) / 4 * longest * longest));
            }
}

/** The APs' transmit array (every AP's with --ap-streams; the two-stream APs' otherwise). */
std::string apArray(const Options& o)
{
    return kShare + "/arrays/ap-linear-" + (o.apStreams == 4 ? "4" : "2") + ".yaml";
}

/** The kidnapped drive's bearings for the runs without odometry: csi-bearings --no-odometry
 *  (a robot without odometry has none for its bearing windows either); bearings.csv in folders
 *  of sweeps made before it. */
fs::path noOdometryBearings(const fs::path& kidnappedDir)
{
    const auto own = kidnappedDir / "bearings-no-odometry.csv";
    return fs::exists(own) ? own : kidnappedDir / "bearings.csv";
}

/** Simulates a drive of the room and runs csi-bearings on it: truth in DIR/truth, bearings in
 *  DIR/bearings.csv (AoD too with --aod), with `alsoWithoutOdometry` also
 *  DIR/bearings-no-odometry.csv from the same frames with the rawlog's odometry ignored; the
 *  rawlog is removed afterwards. */
bool simulateAndEstimate(
    const std::string& scenarioYaml, const fs::path& dir, const fs::path& calib, Room& room,
    const Options& o, bool alsoWithoutOdometry = false)
{
    fs::create_directories(dir);
    std::ofstream(dir / "scenario.yaml") << scenarioYaml;
    const auto rawlog = (dir / "drive.rawlog").string();
    if (runOrThrow(
            bin("wifi-sim") + " " + (dir / "scenario.yaml").string() + " " + rawlog + " -q -t " +
                (dir / "truth").string(),
            room, "wifi-sim")
            .exitCode)
        return false;
    const auto estimate = [&](const std::string& csv, const std::string& extra)
    {
        return runOrThrow(
                   bin("csi-bearings") + " " + rawlog + " /dev/null --calib " + calib.string() +
                       " --csv " + (dir / csv).string() +
                       (o.aod ? " --tx-array " + apArray(o) : "") + extra + " -q",
                   room, "csi-bearings" + extra)
                   .exitCode == 0;
    };
    bool ok = estimate("bearings.csv", "");
    if (ok && alsoWithoutOdometry) ok = estimate("bearings-no-odometry.csv", " --no-odometry");
    fs::remove(rawlog);
    return ok;
}

void runOffline(Room& room, const fs::path& dir, const Options& o)
{
    const auto kt = dir / "kidnapped" / "truth";
    const std::string ini = (dir / "pf.ini").string();
    deriveIni(
        kShare + "/localization/pf-localization-wifi.ini",
        {{"LocalizationExperiment/init_PDF_min_x", "0"},
         {"LocalizationExperiment/init_PDF_max_x", fmt(room.width, 3)},
         {"LocalizationExperiment/init_PDF_min_y", "0"},
         {"LocalizationExperiment/init_PDF_max_y", fmt(room.depth, 3)},
         // the map's area: the room (the robot can't leave it)
         {"MetricMap_wifiBearingMap_00_creationOpts/min_x", "0"},
         {"MetricMap_wifiBearingMap_00_creationOpts/max_x", fmt(room.width, 3)},
         {"MetricMap_wifiBearingMap_00_creationOpts/min_y", "0"},
         {"MetricMap_wifiBearingMap_00_creationOpts/max_y", fmt(room.depth, 3)},
         {"KLD_options/KLD_minSampleSize", std::to_string(o.particles)},
         {"KLD_options/KLD_maxSampleSize", std::to_string(o.particles)}},
        {}, ini);
    for (int odo = 0; odo < 2; ++odo)
    {
        const std::string motion = odo == 0 ? "--odometry-tum " + (kt / "odometry_tum.txt").string()
                                            : "--max-speed " + fmt(room.speed, 3);
        const auto bearings =
            odo == 0 ? dir / "kidnapped" / "bearings.csv" : noOdometryBearings(dir / "kidnapped");
        std::vector<KidnappedFigures> runs;
        for (int seed = 1; seed <= o.offlineSeeds; ++seed)
        {
            // Seed 1 keeps the folder of a single run.
            const auto out = dir / ((odo == 0 ? "pf-odometry" : "pf-no-odometry") +
                                    (seed > 1 ? "-seed" + std::to_string(seed) : ""));
            const auto r = runOrThrow(
                bin("wifi-pf-localization") + " " + ini + " -q --no-plots -n " +
                    std::to_string(o.particles) + " --seed " + std::to_string(seed) + " -m " +
                    (kt / "transmitters.yaml").string() + " -b " + bearings.string() + " " +
                    kSensorPose + " " + motion + " -o " + out.string(),
                room,
                std::string("wifi-pf-localization (") + kRunNames[0][odo] + ", seed " +
                    std::to_string(seed) + ")");
            if (r.exitCode != 0) continue;
            runs.push_back(kidnappedFigures(
                Trajectory2D::fromTumFile((out / "estimate_tum.txt").string()), room.kidnappedTruth,
                o));
            room.offlineRuns_m[odo].push_back(kidnappedMedian(runs.back()));
            if (odo == 1 && seed == 1) room.noOdoSharp3Share = sharp3Share(out / "summary.txt");
        }
        if (!runs.empty()) room.kidnapped[0][odo] = medianRun(std::move(runs));
    }
}

/** loctest::trackFromTruth on the kidnapped drive of the room in `dir` (a room folder of a
 *  sweep), configured as wifi-pf-localization runs the room's pf.ini without odometry. */
loctest::TrackFromTruth trackFromTruthOfRoom(const fs::path& dir)
{
    const auto pfIni = dir / "pf.ini", kt = dir / "kidnapped" / "truth";
    if (!fs::exists(pfIni)) throw std::runtime_error("no " + pfIni.string());
    const mrpt::config::CConfigFile ini(pfIni.string());
    WindowSmootherOptions options;
    options.loadFromConfigFile(ini, "WindowSmoother");
    UnknownMotion motion;
    motion.loadFromConfigFile(ini, "UnknownMotion");
    options.track.forwardOnly = motion.forwardOnly;
    const std::string likelihood = "MetricMap_wifiBearingMap_00_likelihoodOpts";
    options.graph.useAoa = ini.read_bool(likelihood, "use_aoa", true);
    options.graph.useAod = ini.read_bool(likelihood, "use_aod", true);
    const std::string creation = "MetricMap_wifiBearingMap_00_creationOpts";
    const mrpt::math::TBoundingBox area(
        {ini.read_double(creation, "min_x", 0, true), ini.read_double(creation, "min_y", 0, true),
         0},
        {ini.read_double(creation, "max_x", 0, true), ini.read_double(creation, "max_y", 0, true),
         0});
    const auto aps = TransmitterMap::fromYamlFile((kt / "transmitters.yaml").string());
    BearingCsvOptions co;
    co.sensorPose = kSensorPose2D;
    co.names = &aps;
    const auto bearings = readBearingCsv(noOdometryBearings(dir / "kidnapped").string(), co);
    const auto truth = Trajectory2D::fromTumFile((kt / "trajectory_tum.txt").string());
    return loctest::trackFromTruth(bearings, aps, truth, options, area);
}

/** One live run of runLive(), with filter seed `seed` (1 keeps the folder of a single run);
 *  its figures, or nothing when it failed (named in the room's errors). */
std::optional<KidnappedFigures> runLiveOnce(
    Room& room, const fs::path& dir, const fs::path& calib, const Options& o,
    const std::string& scenario, int odo, int seed)
{
    const uint16_t csiPort = test::freeLoopbackPort(SOCK_DGRAM);
    uint16_t odoPort = test::freeLoopbackPort(SOCK_DGRAM);
    if (odoPort == csiPort) odoPort = uint16_t(csiPort + 1);
    const auto out = dir / ((odo == 0 ? "live-odometry" : "live-no-odometry") +
                            (seed > 1 ? "-seed" + std::to_string(seed) : ""));
    const std::string ini = out.string() + ".ini";
    // wifi-localize's chain is always configured (it is built either way); with the
    // sensor's, wifi-localize uses that sensor's bearings instead. The sensor takes its
    // transmit arrays as a list (`[MAC=]FILE`): one default here.
    std::map<std::string, std::string> keys = {
        {"WIFI_CSI/udp_port", std::to_string(csiPort)},
        {"ODOMETRY/udp_port", std::to_string(odoPort)},
        {"MetricMap_wifiBearingMap_00_creationOpts/transmitters_file",
         (dir / "kidnapped" / "truth" / "transmitters.yaml").string()},
        {"MetricMap_wifiBearingMap_00_likelihoodOpts/use_aoa", "true"},
        {"MetricMap_wifiBearingMap_00_likelihoodOpts/use_aod", o.aod ? "true" : "false"},
        {"LocalizationExperiment/particles_count", std::to_string(o.particles)},
        {"LocalizationExperiment/init_PDF_max_x", fmt(room.width, 3)},
        {"LocalizationExperiment/init_PDF_max_y", fmt(room.depth, 3)},
        {"KLD_options/KLD_minSampleSize", std::to_string(o.particles)},
        {"KLD_options/KLD_maxSampleSize", std::to_string(o.particles)},
        // the robot's top speed, as --max-speed offline (the offline [UnknownMotion])
        {"UnknownMotion/max_speed_mps", fmt(room.speed, 3)}};
    const auto configureChain = [&](const std::string& section, const std::string& txKey)
    {
        keys[section + "/bearing_algorithm"] = "default";
        keys[section + "/bearing_calibration"] = calib.string();
        keys[section + "/bearing_array"] = kShare + "/arrays/rt-ac86u.yaml";
        keys[section + "/" + txKey] = apArray(o);
    };
    configureChain("wifi-localize", "bearing_tx_arrays");
    if (o.liveChain == "sensor") configureChain("WIFI_CSI", "bearing_tx_arrays");
    deriveIni(
        kShare + "/localization/wifi-localize-emulator.ini", keys,
        odo == 0 ? std::set<std::string>{} : std::set<std::string>{"ODOMETRY"}, ini);
    std::vector<std::string> emuArgs = {"--scenario", scenario, "--preconfigured", "155/80", "-q"};
    if (odo == 0) emuArgs.insert(emuArgs.end(), {"--odometry-port", std::to_string(odoPort)});
    // wifi-localize first, and the emulator only once it listens: the live run then gets
    // the drive from its first frame, as the offline run does. Started after the emulator,
    // it missed the first 0.35-0.55 s, and a filter without odometry that starts later can
    // settle on another track (development room 39, fed two bearings per step: from the
    // first frame 0 of 6 filter seeds lost the robot, from where a live run started 5 of
    // 6), so the live/offline ratio compared two different runs.
    const std::string liveCommand = "timeout " + std::to_string(int(o.kidnappedDuration_s + 90)) +
                                    " " + bin("wifi-localize") + " -p " + test::libDir() +
                                    "/libmrpt_wifi_sensor.so " + ini + " -q -o " + out.string() +
                                    " -d " + fmt(o.kidnappedDuration_s + 30, 1) +
                                    " --stop-when-idle 3 --seed " + std::to_string(seed);
    auto live = std::async(std::launch::async, [&] { return test::run(liveCommand); });
    bool listening = test::waitForUdpListener(csiPort, std::chrono::seconds(30));
    if (odo == 0)
        listening = listening && test::waitForUdpListener(odoPort, std::chrono::seconds(5));
    Trajectory2D truth;  // the emulator's, on the receiver's clock (as the live estimate)
    test::CommandResult r;
    {
        // Not listening: the emulator still runs (wifi-localize then stops when idle or at
        // -d) and the error below names wifi-localize.
        test::EmulatorProcess emu(emuArgs, csiPort, o.kidnappedDuration_s + 5);
        const bool emulatorReady = emu.ready();  // its socket goes when it stops
        r = live.get();
        emu.stop();
        if (!emulatorReady)
        {
            room.errors.push_back("rt-ac86u-emulator");
            std::cerr << "\n[localization-accuracy] emulator not ready:\n" << emu.log();
            return std::nullopt;
        }
        const std::string truthFile = emu.stateDir() + "/truth/trajectory_tum.txt";
        if (fs::exists(truthFile)) truth = Trajectory2D::fromTumFile(truthFile);
    }
    const std::string what =
        std::string("wifi-localize (") + kRunNames[1][odo] + ", seed " + std::to_string(seed) + ")";
    if (!listening || r.exitCode != 0)
    {
        reportFailure(
            room, what,
            listening ? "failed (exit " + std::to_string(r.exitCode) + ")"
                      : "never listened on its UDP ports",
            liveCommand, r.output);
        return std::nullopt;
    }
    if (truth.empty() || !fs::exists(out / "estimate_tum.txt") ||
        fs::file_size(out / "estimate_tum.txt") == 0)
        return std::nullopt;
    // Both on the receiver's clock: compared as they are.
    const auto est = Trajectory2D::fromTumFile((out / "estimate_tum.txt").string());
    auto k = kidnappedFigures(est, truth, o, readEstimateCovariances(out / "estimate_cov.csv"));
    room.liveRuns_m[odo].push_back(kidnappedMedian(k));
    room.liveLagP99_ms[odo].push_back(liveLagP99_ms(out / "summary.txt"));
    return k;
}

/** wifi-localize on the room streamed by the emulator in real time (CSI and, with odometry,
 *  the odometry stream), the bearings from its own chain or the CSI sensor's (Options::liveChain),
 *  configured as csi-bearings runs it; Options::liveSeeds runs each, the median one the room's. */
void runLive(Room& room, const fs::path& dir, const fs::path& calib, const Options& o)
{
    const auto scenario = (dir / "kidnapped" / "scenario.yaml").string();
    for (int odo = 0; odo < 2; ++odo)
    {
        std::vector<KidnappedFigures> runs;
        for (int seed = 1; seed <= o.liveSeeds; ++seed)
            if (auto k = runLiveOnce(room, dir, calib, o, scenario, odo, seed))
                runs.push_back(std::move(*k));
        if (!runs.empty()) room.kidnapped[1][odo] = medianRun(std::move(runs));
    }
}

void runLoop(Room& room, const fs::path& dir)
{
    const auto lt = dir / "loop" / "truth";
    const auto csv = (dir / "loop" / "bearings.csv").string();
    const auto odometry = (lt / "odometry_tum.txt").string();
    for (int est = 0; est < 2; ++est)
    {
        const auto out = dir / (est == 0 ? "slam-known-aps" : "slam-estimated-aps");
        const auto r = runOrThrow(
            bin("wifi-graphslam") + " -b " + csv + " --odometry-tum " + odometry + " --aps " +
                (lt / "transmitters.yaml").string() +
                (est ? " --estimate-aps --true-aps " + (lt / "transmitters.yaml").string() : "") +
                " " + kSensorPose + " -g " + (lt / "trajectory_tum.txt").string() + " -o " +
                out.string() + " --no-plots",
            room, est == 0 ? "wifi-graphslam --aps" : "wifi-graphslam --estimate-aps");
        if (r.exitCode != 0) continue;
        auto& d = room.drift[est];
        const auto solution = Trajectory2D::fromTumFile((out / "trajectory_tum.txt").string());
        const auto odometryNodes =
            Trajectory2D::fromTumFile((out / "odometry_nodes_tum.txt").string());
        const auto slam = absoluteTrajectoryError(solution, room.loopTruth);
        d.ran = true;
        d.slamAte_m = slam.stats.median;
        d.odometryAte_m = absoluteTrajectoryError(odometryNodes, room.loopTruth).stats.median;
        d.reduction = 1 - d.slamAte_m / d.odometryAte_m;
        d.scaleFreeReduction =
            1 - absoluteTrajectoryError(solution, room.loopTruth, true, true).stats.median /
                    absoluteTrajectoryError(odometryNodes, room.loopTruth, true, true).stats.median;
        d.aligned = solution;
        const mrpt::poses::CPose2D T(slam.alignment);
        for (auto& p : d.aligned.poses) p = (T + mrpt::poses::CPose2D(p)).asTPose();
    }

    // Device mapping from odometry: the APs are the devices; the odometry's first pose is put
    // at the true start (the map is in the odometry frame otherwise).
    const auto& p0 = room.loopTruth.poses.front();
    const auto out = dir / "devices";
    const auto r = runOrThrow(
        bin("wifi-iot-map") + " -b " + csv + " --odometry-tum " + odometry + " --initial-pose \"" +
            fmt(p0.x, 4) + " " + fmt(p0.y, 4) + " " + fmt(p0.phi * 180 / M_PI, 3) + "\" " +
            kSensorPose + " --truth " + (lt / "transmitters.yaml").string() + " -q --no-plots -o " +
            out.string(),
        room, "wifi-iot-map --odometry-tum");
    if (r.exitCode != 0) return;
    const auto truthMap = TransmitterMap::fromYamlFile((lt / "transmitters.yaml").string());
    auto& dv = room.devices;
    dv.ran = true;
    std::ifstream f(out / "devices.csv");
    std::string line;
    std::getline(f, line);  // mac,name,localized,x_m,y_m,cov_xx,cov_xy,cov_yy,...,note
    std::vector<double> errs;
    while (std::getline(f, line))
    {
        std::vector<std::string> c;
        std::istringstream s(line);
        for (std::string x; std::getline(s, x, ',');) c.push_back(x);
        if (c.size() < 8) continue;
        ++dv.devices;
        if (line.find("weak geometry") != std::string::npos) dv.weak.push_back(c[1]);
        if (c[2] != "1") continue;
        const KnownTransmitter* t = nullptr;
        for (const auto& k : truthMap.transmitters())
            if (k.mac.asString() == c[0]) t = &k;
        if (!t) continue;
        ++dv.localized;
        const double x = std::stod(c[3]), y = std::stod(c[4]);
        const double a = std::stod(c[5]), b = std::stod(c[6]), cc = std::stod(c[7]);
        dv.estimates.push_back({x, y, a, b, cc});
        const double ex = x - t->pose.x, ey = y - t->pose.y;
        errs.push_back(std::hypot(ex, ey));
        dv.inside += mahalanobis2(a, b, cc, ex, ey) <= kChi2TwoDof95;
    }
    // A device the mapper could not place counts as outside its ellipse.
    dv.insideShare = dv.devices ? double(dv.inside) / double(dv.devices) : NAN;
    dv.medianError_m = errs.empty() ? NAN : computeStats(errs).median;
    dv.maxError_m = errs.empty() ? NAN : computeStats(errs).max;
}

/** Odometry errors of a room, drawn from its seed: scale 1–3 % either way, rotation scale up
 *  to ±2 %, heading drift 0.1–0.6 °/m either way (a wheeled robot on an office floor; the
 *  issue's example: 3 % and 0.5 °/s). */
void drawOdometryErrors(Room& room)
{
    mrpt::random::CRandomGenerator rng(room.seed * 2654435761u + 0x0d0);
    const auto sign = [&] { return rng.drawUniform(0, 1) < 0.5 ? -1.0 : 1.0; };
    room.scaleError = sign() * rng.drawUniform(0.01, 0.03);
    room.yawScaleError = rng.drawUniform(-0.02, 0.02);
    room.yawDrift_deg_per_m = sign() * rng.drawUniform(0.1, 0.6);
}

/** A case study that fails with an error costs that case in that room, not the sweep: the
 *  error is recorded with the room (and listed with it) and the others go on. */
void guarded(Room& room, const std::string& what, const std::function<void()>& run)
{
    try
    {
        run();
    }
    catch (const std::exception& e)
    {
        room.errors.push_back(what + ": " + e.what());
        std::cerr << "\n[localization-accuracy] room " << room.seed << ", " << what << ": "
                  << e.what() << "\n";
    }
}

constexpr double kApCalibration_s = 60;  //!< the AP calibration drive (the loop's first part)

/** The APs' transmit chains calibrated as a user would: wifi-calibrate --transmit-chains on the
 *  first kApCalibration_s of the room's loop drive with its odometry (started where the loop
 *  starts), written beside the receiver's calibration (`calib/transmitters`). The receiver's own
 *  calibration stays the simulator's truth. */
void calibrateTransmitChains(
    Room& room, const fs::path& dir, const std::string& loopYaml, const fs::path& calib)
{
    const fs::path cd = dir / "ap-calibration";
    fs::create_directories(cd);
    std::ofstream(cd / "scenario.yaml") << loopYaml;
    const auto rawlog = (cd / "drive.rawlog").string();
    const auto start = sim::Scenario::fromYamlText(loopYaml, "room", ".").motion.start;
    if (runOrThrow(
            bin("wifi-sim") + " " + (cd / "scenario.yaml").string() + " " + rawlog + " -q -d " +
                fmt(kApCalibration_s, 0) + " -t " + (cd / "truth").string(),
            room, "wifi-sim (AP calibration drive)")
            .exitCode == 0)
        runOrThrow(
            bin("wifi-calibrate") + " " + rawlog + " --array " + kShare +
                "/arrays/rt-ac86u.yaml --transmitters " +
                (cd / "truth" / "transmitters.yaml").string() + " --poses odometry --odom-origin " +
                fmt(start.x, 3) + " " + fmt(start.y, 3) + " " + fmt(mrpt::RAD2DEG(start.phi), 2) +
                " --transmit-chains --force -q --out " + (cd / "out").string(),
            room, "wifi-calibrate --transmit-chains");
    fs::remove(rawlog);
    if (fs::exists(cd / "out" / "transmitters"))
        fs::copy(
            cd / "out" / "transmitters", calib / "transmitters",
            fs::copy_options::recursive | fs::copy_options::overwrite_existing);
}

Room evaluateRoom(uint32_t seed, const Options& o)
{
    const auto wall0 = std::chrono::steady_clock::now();
    Room room;
    room.seed = seed;
    drawOdometryErrors(room);
    const fs::path dir = o.work / ("room-" + std::to_string(seed));
    fs::create_directories(dir);

    sim::RandomRoomOptions ro;
    ro.arraysDir = kShare + "/arrays";
    ro.accessPoints = o.accessPoints;
    ro.duration_s = o.kidnappedDuration_s;
    ro.odometryScaleError = room.scaleError;
    ro.odometryYawScaleError = room.yawScaleError;
    ro.odometryYawDrift_deg_per_m = room.yawDrift_deg_per_m;
    ro.accessPointStreams = o.apStreams;
    const std::string kidnappedYaml = sim::randomRoomYaml(seed, ro);
    ro.loopLaps = o.laps;
    const std::string loopYaml = sim::randomRoomYaml(seed, ro);

    const sim::Scenario sc = sim::Scenario::fromYamlText(kidnappedYaml, "room", ".");
    for (const auto& w : sc.walls)
        room.width = std::max({room.width, w.from.x, w.to.x}),
        room.depth = std::max({room.depth, w.from.y, w.to.y});
    room.speed = sc.motion.speed_mps;
    for (const auto& t : sc.transmitters) room.aps.push_back({t.pose.x, t.pose.y});
    apGeometry(room);

    // The receiver calibrated with the simulator's true offsets (drawn from the room's seed).
    const fs::path calib = dir / "calib";
    {
        sim::Simulator simulator(sc);
        const AntennaArray rx = test::fromSimArray(sc.receiver.array);
        const auto cal = test::truthCalibration(simulator, rx, sc.transmitters.front().chanspec);
        cal.saveYamlFile(PhaseCalibration::pathFor(calib.string(), rx.name, cal.chanspec));
    }
    const AntennaArray rx = test::fromSimArray(sc.receiver.array);
    if (o.aod)
    {
        std::cerr << "[room " << seed << "] AP calibration drive" << std::flush;
        guarded(
            room, "transmit-chain calibration",
            [&] { calibrateTransmitChains(room, dir, loopYaml, calib); });
        std::cerr << "\n";
    }

    std::vector<test::ErrorRecord> bearingErrors;
    std::cerr << "[room " << seed << "] kidnapped drive" << std::flush;
    if (simulateAndEstimate(kidnappedYaml, dir / "kidnapped", calib, room, o, true))
    {
        room.kidnappedTruth =
            Trajectory2D::fromTumFile((dir / "kidnapped/truth/trajectory_tum.txt").string());
        addBearingErrors(
            (dir / "kidnapped/bearings.csv").string(),
            (dir / "kidnapped/truth/frames.csv").string(), rx, bearingErrors);
        std::cerr << ", offline PF" << std::flush;
        guarded(room, "offline PF", [&] { runOffline(room, dir, o); });
        guarded(
            room, "track from the true poses",
            [&]
            {
                const auto t = trackFromTruthOfRoom(dir);
                room.noOdoTrackFromTruth_m = t.median_m;
                room.noOdoTrackFromTruthFull_m = t.fullWindowMedian_m;
            });
        if (o.live)
        {
            std::cerr << ", live" << std::flush;
            guarded(room, "live", [&] { runLive(room, dir, calib, o); });
        }
    }
    const size_t kidnappedBearings = bearingErrors.size();
    std::cerr << ", loop drive" << std::flush;
    if (simulateAndEstimate(loopYaml, dir / "loop", calib, room, o))
    {
        room.loopTruth =
            Trajectory2D::fromTumFile((dir / "loop/truth/trajectory_tum.txt").string());
        room.loopOdometry =
            Trajectory2D::fromTumFile((dir / "loop/truth/odometry_tum.txt").string());
        addBearingErrors(
            (dir / "loop/bearings.csv").string(), (dir / "loop/truth/frames.csv").string(), rx,
            bearingErrors);
        std::cerr << ", graph SLAM, device map" << std::flush;
        guarded(room, "graph SLAM / device map", [&] { runLoop(room, dir); });
    }
    room.bearings = BearingFigures::of(bearingErrors);
    room.bearingsOfDrive[1] = BearingFigures::of(std::vector<test::ErrorRecord>(
        bearingErrors.begin() + long(kidnappedBearings), bearingErrors.end()));
    bearingErrors.resize(kidnappedBearings);
    room.bearingsOfDrive[0] = BearingFigures::of(bearingErrors);
    room.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    return room;
}

// ---- targets ---------------------------------------------------------------------------------

/** One row of the summary: a per-room pass/fail, the figure shown, and the share of rooms that
 *  must pass (1 = every room). */
struct Target
{
    std::string figure, target;
    double requiredShare;
    std::function<double(const Room&)> value;  //!< NaN: not measured (counts as a miss)
    std::function<bool(double)> pass;
    int digits = 2;
};

std::vector<Target> targets(bool live)
{
    std::vector<Target> t;
    for (int l = 0; l < (live ? 2 : 1); ++l)
        for (int odo = 0; odo < 2; ++odo)
            t.push_back(
                {std::string("kidnapped ") + kRunNames[l][odo] +
                     ": median error after convergence [m]",
                 "≤ 0.3 m (never converged: ∞)", 0.9,
                 [l, odo](const Room& r) { return kidnappedMedian(r.kidnapped[l][odo]); },
                 [](double v) { return v <= 0.3; }});
    if (live)
        for (int odo = 0; odo < 2; ++odo)
            t.push_back(
                {std::string("kidnapped live / offline, ") + (odo ? "no odometry" : "odometry"),
                 "≤ 1.3×", 0.9,
                 [odo](const Room& r) {
                     return kidnappedMedian(r.kidnapped[1][odo]) /
                            kidnappedMedian(r.kidnapped[0][odo]);
                 },
                 [](double v) { return v <= 1.3; }});
    if (live)
        for (int odo = 0; odo < 2; ++odo)
            t.push_back(
                {std::string("kidnapped live, ") + (odo ? "no odometry" : "odometry") +
                     ": estimates after convergence inside the filter's 95 % ellipse [%]",
                 "≥ 90 %", 0.9,
                 [odo](const Room& r) { return 100 * r.kidnapped[1][odo].inside95After; },
                 [](double v) { return v >= 90; }, 0});
    t.push_back(
        {"kidnapped offline: no odometry / odometry", "≤ 2× (issue 19.2)", 0.9,
         [](const Room& r)
         { return kidnappedMedian(r.kidnapped[0][1]) / kidnappedMedian(r.kidnapped[0][0]); },
         [](double v) { return v <= 2; }});
    for (int e = 0; e < 2; ++e)
        t.push_back(
            {std::string("drift correction, ") + (e ? "estimated" : "known") +
                 " APs: median ATE reduction vs odometry [%]",
             "≥ 60 %", 0.9,
             [e](const Room& r) { return r.drift[e].ran ? 100 * r.drift[e].reduction : NAN; },
             [](double v) { return v >= 60; }, 1});
    t.push_back(
        {"drift correction: known − estimated [points]", "≥ −5", 1.0,
         [](const Room& r)
         {
             return r.drift[0].ran && r.drift[1].ran
                        ? 100 * (r.drift[0].reduction - r.drift[1].reduction)
                        : NAN;
         },
         [](double v) { return v >= -5; }, 1});
    t.push_back(
        {"device map: median device error [m]", "≤ 0.5 m", 0.9,
         [](const Room& r) { return r.devices.medianError_m; }, [](double v) { return v <= 0.5; }});
    t.push_back(
        {"device map: devices inside their 95 % ellipse [%]", "≥ 90 %", 0.9,
         [](const Room& r) { return 100 * r.devices.insideShare; },
         [](double v) { return v >= 90; }, 0});
    t.push_back(
        {"bearings beyond 30° (within 75° of broadside) [%]", "≤ 2 %", 0.9,
         [](const Room& r) { return 100 * r.bearings.centralBeyond30; },
         [](double v) { return v <= 2; }});
    t.push_back(
        {"bearings beyond 30° and beyond their alternatives (within 75° of broadside) [%]", "≤ 2 %",
         0.9, [](const Room& r) { return 100 * r.bearings.centralBeyond30AndAlternatives; },
         [](double v) { return v <= 2; }});
    t.push_back(
        {"bearings beyond 30° (within 75° of broadside) [%]", "≤ 5 % in every room", 1.0,
         [](const Room& r) { return 100 * r.bearings.centralBeyond30; },
         [](double v) { return v <= 5; }});
    return t;
}

/** The median, also of values that include ∞ (runs that never converged). */
double medianOf(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : (std::isinf(v[n / 2]) ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

bool passes(const Target& t, const Room& r)
{
    const double v = t.value(r);
    return !std::isnan(v) && t.pass(v);
}

/** A live run's lag p99 beyond which it fell behind the stream: wifi-localize batches what
 *  queued for over max_queue_s (250 ms as shipped) into one filter step. */
constexpr double kBehindStream_ms = 250;

/** Why a room misses: the measurable suspects, each with the rule that names it; a rule about
 *  one target (`ts`) speaks only when that target missed. */
std::string whyItFails(const Room& r, const std::vector<Target>& ts)
{
    // Whether a target whose figure starts with `prefix` missed in this room.
    const auto missed = [&](const std::string& prefix)
    {
        return std::any_of(
            ts.begin(), ts.end(),
            [&](const Target& t) { return t.figure.rfind(prefix, 0) == 0 && !passes(t, r); });
    };
    std::vector<std::string> why;
    // How often the bearings alone fixed a pose, beside an information reason.
    const std::string sharpSeconds =
        std::isnan(r.noOdoSharp3Share) ? std::string()
                                       : "; 3 or more APs with a sharp bearing in " +
                                             fmt(100 * r.noOdoSharp3Share, 0) + " % of its seconds";
    if (r.apMinSeparation_m < 1.5 || r.apTriangle < 0.15)
        why.push_back(
            "geometry (APs " + fmt(r.apMinSeparation_m, 1) + " m apart at the closest, triangle " +
            fmt(r.apTriangle, 2) + " of equilateral)");
    if (!r.devices.weak.empty())
    {
        std::string names;
        for (const auto& n : r.devices.weak) names += (names.empty() ? "" : ", ") + n;
        why.push_back("geometry (weak ray spread: " + names + ")");
    }
    if (r.bearings.centralBeyond30 > 0.02 || r.bearings.centralMedian_deg > 3)
        why.push_back(
            "multipath (bearings: median " + fmt(r.bearings.centralMedian_deg, 1) + "°, " +
            fmt(100 * r.bearings.centralBeyond30, 1) + " % beyond 30°, " +
            fmt(100 * r.bearings.centralBeyond30Unflagged, 1) + " % also beyond 3σ)");
    // Without odometry, the track fitted from the true poses tells the two apart: off too, the
    // bearings leave the pose open (information); close, the filter settled elsewhere.
    const auto misses = [](const KidnappedFigures& k)
    { return k.ran && (!k.converged || k.medianAfter_m > 0.3); };
    const bool noOdoMisses = misses(r.kidnapped[0][1]) || misses(r.kidnapped[1][1]);
    if (noOdoMisses && r.noOdoTrackFromTruth_m > 0.3)
        why.push_back(
            "information (without odometry a track fitted from the true poses is itself " +
            fmt(r.noOdoTrackFromTruth_m) + " m off at its newest pose" + sharpSeconds + ")");
    // The same best case against the error with odometry: beyond 2× of it, so is the target.
    const double odoMedian = kidnappedMedian(r.kidnapped[0][0]);
    const double trackRatio = r.noOdoTrackFromTruthFull_m / odoMedian;
    const double noOdoMedian = kidnappedMedian(r.kidnapped[0][1]);
    if (noOdoMedian > 2 * odoMedian && trackRatio > 2)
        why.push_back(
            "information (without odometry a track fitted from the true poses is itself " +
            fmt(trackRatio, 1) + "× the error with odometry over its full windows" + sharpSeconds +
            ")");
    // ... within 2× of it, the bearings held what the filter without odometry did not find.
    if (noOdoMedian > 2 * odoMedian && trackRatio <= 2)
        why.push_back(
            "the search (without odometry the filter is " + fmt(noOdoMedian / odoMedian, 1) +
            "× the error with odometry while a track fitted from the true poses is " +
            fmt(trackRatio, 1) + "× over its full windows)");
    // A live run far behind the stream measured the machine's load.
    for (int odo = 0; odo < 2; ++odo)
    {
        const bool liveMisses =
            missed(std::string("kidnapped ") + kRunNames[1][odo] + ": median") ||
            missed(std::string("kidnapped live / offline, ") + (odo ? "no odometry" : "odometry"));
        const auto& lags = r.liveLagP99_ms[odo];
        const double worstLag = lags.empty() ? NAN : *std::max_element(lags.begin(), lags.end());
        if (liveMisses && worstLag > kBehindStream_ms)
            why.push_back(
                std::string("real time (") + kRunNames[1][odo] + ": a run's lag p99 " +
                fmt(worstLag, 0) + " ms, behind the stream)");
    }
    // A filter that settles away from the robot with clean bearings found another pose that
    // explains them (the linear array's mirror, or a symmetric AP layout).
    for (int odo = 0; odo < 2; ++odo)
    {
        const auto& k = r.kidnapped[0][odo];
        const bool trackFits = r.noOdoTrackFromTruth_m <= 0.3;
        const bool suspect = odo == 1 && !std::isnan(r.noOdoTrackFromTruth_m)
                                 ? trackFits
                                 : r.bearings.centralBeyond30 <= 0.02;
        if (misses(k) && suspect)
        {
            why.push_back(
                std::string("ambiguity (") + kRunNames[0][odo] + ": " +
                (k.converged ? "median " + fmt(k.medianAfter_m) + " m"
                             : "never converged, worst " + fmt(k.worstAll_m, 1) + " m") +
                (odo == 1 && trackFits ? " while a track fitted from the true poses is " +
                                             fmt(r.noOdoTrackFromTruth_m) + " m off"
                                       : std::string(" with clean bearings")) +
                ")");
            break;
        }
    }
    // The devices' σ holds the odometry's noise, not its systematic scale error (bearings
    // cannot observe scale): with a large one the ellipses are too small.
    if (r.devices.ran && r.devices.insideShare < 0.9)
        why.push_back(
            "odometry (scale error " + fmt(100 * r.scaleError, 1) + " %, heading drift " +
            fmt(r.yawDrift_deg_per_m, 2) + "°/m: not in the devices' σ)");
    // Bearings are angles: with estimated APs the map's scale is the odometry's. When taking
    // the scale out (a similarity alignment) meets the target, the rest was corrected.
    if (r.drift[1].ran && r.drift[1].reduction < 0.6 && r.drift[1].scaleFreeReduction >= 0.6)
        why.push_back(
            "odometry scale (estimated APs: " + fmt(100 * r.drift[1].scaleFreeReduction, 0) +
            " % reduction without the scale, which bearings cannot observe; odometry scale "
            "error " +
            fmt(100 * r.scaleError, 1) + " %)");
    if (missed("drift correction") && r.drift[0].ran && r.drift[0].odometryAte_m < 0.3)
        why.push_back(
            "little drift to remove (odometry ATE " + fmt(r.drift[0].odometryAte_m) + " m)");
    if (!r.errors.empty()) why.push_back("a program failed: " + r.errors.front());
    std::string s;
    for (const auto& w : why) s += (s.empty() ? "" : "; ") + w;
    return s.empty() ? "none of the rules (see the pictures)" : s;
}

/** The room's two pictures: the kidnapped drive (truth, offline and live estimates, APs) and
 *  the loop (truth, odometry, both graph-SLAM solutions, devices with their 95 % ellipses). */
void drawRoom(const Room& r, const fs::path& dir)
{
    const auto series = [](const Trajectory2D& t, const std::string& title, const std::string& st)
    {
        plot::Series s{title, {}, {}, st};
        for (const auto& p : t.poses) s.x.push_back(p.x), s.y.push_back(p.y);
        return s;
    };
    plot::Series walls{
        "walls",
        {0, r.width, r.width, 0, 0},
        {0, 0, r.depth, r.depth, 0},
        "lines lw 3 lc rgb '#777777'"};
    plot::Series aps{"access points (truth)", {}, {}, "points pt 5 ps 2 lc rgb '#1f77b4'"};
    for (const auto& a : r.aps) aps.x.push_back(a.x), aps.y.push_back(a.y);
    std::string err;
    {
        plot::Figure f;
        f.title = "room " + std::to_string(r.seed) + ": kidnapped robot (estimates vs truth)";
        f.xlabel = "x [m]", f.ylabel = "y [m]", f.equalAxes = true;
        f.series = {walls, series(r.kidnappedTruth, "truth", "lines lw 2 lc rgb '#333333'")};
        const char* colours[2][2] = {{"#d62728", "#ff7f0e"}, {"#2ca02c", "#9467bd"}};
        for (int l = 0; l < 2; ++l)
            for (int odo = 0; odo < 2; ++odo)
                if (r.kidnapped[l][odo].ran)
                    f.series.push_back(series(
                        r.kidnapped[l][odo].estimate, kRunNames[l][odo],
                        std::string("lines lw 1 lc rgb '") + colours[l][odo] + "'"));
        f.series.push_back(aps);
        if (!plot::savePng(
                f, (dir / ("room-" + std::to_string(r.seed) + "-kidnapped.png")).string(), &err))
            std::cerr << "warning: " << err << "\n";
    }
    {
        plot::Figure f;
        f.title = "room " + std::to_string(r.seed) + ": loop (graph SLAM, device map)";
        f.xlabel = "x [m]", f.ylabel = "y [m]", f.equalAxes = true;
        f.series = {walls, series(r.loopTruth, "truth", "lines lw 2 lc rgb '#333333'")};
        // Odometry from the true start (it starts at its own origin).
        if (!r.loopOdometry.empty() && !r.loopTruth.empty())
        {
            Trajectory2D odo = r.loopOdometry;
            const mrpt::poses::CPose2D T = mrpt::poses::CPose2D(r.loopTruth.poses.front()) -
                                           mrpt::poses::CPose2D(odo.poses.front());
            for (auto& p : odo.poses) p = (T + mrpt::poses::CPose2D(p)).asTPose();
            f.series.push_back(series(odo, "odometry", "lines lw 1 dt 2 lc rgb '#8c564b'"));
        }
        if (r.drift[0].ran)
            f.series.push_back(
                series(r.drift[0].aligned, "graph SLAM, known APs", "lines lw 1 lc rgb '#2ca02c'"));
        if (r.drift[1].ran)
            f.series.push_back(series(
                r.drift[1].aligned, "graph SLAM, estimated APs (aligned)",
                "lines lw 1 lc rgb '#d62728'"));
        f.series.push_back(aps);
        plot::Series dev{"devices (odometry map)", {}, {}, "points pt 7 ps 1.5 lc rgb '#e377c2'"};
        for (const auto& d : r.devices.estimates)
        {
            dev.x.push_back(d[0]), dev.y.push_back(d[1]);
            f.series.push_back(plot::ellipse(
                d[0], d[1], d[2], d[3], d[4], std::sqrt(kChi2TwoDof95), "",
                "lines lw 1 lc rgb '#e377c2'"));
        }
        f.series.push_back(dev);
        if (!plot::savePng(
                f, (dir / ("room-" + std::to_string(r.seed) + "-loop.png")).string(), &err))
            std::cerr << "warning: " << err << "\n";
    }
}

void writeCsv(const std::vector<Room>& rooms, const std::string& path)
{
    std::ofstream f(path);
    if (!f) throw std::runtime_error("cannot write '" + path + "'");
    f << "seed,width_m,depth_m,speed_mps,odo_scale_error,odo_yaw_scale_error,"
         "odo_yaw_drift_deg_per_m,ap_min_separation_m,ap_triangle";
    const char* runs[4] = {"offline_odo", "offline_noodo", "live_odo", "live_noodo"};
    for (const char* r : runs)
        f << "," << r << "_median_m," << r << "_converge_s," << r << "_worst_after_m," << r
          << "_worst_all_m," << r << "_inside95_after," << r << "_inside3sigma_after," << r
          << "_start_s";
    f << ",ate_odometry_m,ate_known_m,reduction_known,ate_estimated_m,reduction_estimated,"
         "reduction_known_scale_free,reduction_estimated_scale_free,"
         "devices,devices_localized,device_median_m,device_max_m,devices_inside_95,"
         "bearings,bearings_central,central_beyond30,all_beyond30,central_median_deg,"
         "central_beyond30_unflagged,"
         "random_drive_central_beyond30,loop_central_beyond30,noodo_track_from_truth_m,"
         "noodo_track_full_windows_m,noodo_sharp3_seconds,offline_odo_runs_m,offline_noodo_runs_m,"
         "live_odo_runs_m,"
         "live_noodo_runs_m,live_odo_lag_p99_ms,live_noodo_lag_p99_ms,wall_s,failed_programs,"
         "central_beyond30_and_alternatives,central_within_3sigma,alternatives_per_bearing\n";
    for (const auto& r : rooms)
    {
        f << r.seed << "," << r.width << "," << r.depth << "," << r.speed << "," << r.scaleError
          << "," << r.yawScaleError << "," << r.yawDrift_deg_per_m << "," << r.apMinSeparation_m
          << "," << r.apTriangle;
        for (int l = 0; l < 2; ++l)
            for (int odo = 0; odo < 2; ++odo)
            {
                const auto& k = r.kidnapped[l][odo];
                f << "," << kidnappedMedian(k) << "," << k.timeToConverge_s << "," << k.worstAfter_m
                  << "," << k.worstAll_m << "," << k.inside95After << "," << k.inside3SigmaAfter
                  << "," << k.start_s;
            }
        f << "," << r.drift[0].odometryAte_m << "," << r.drift[0].slamAte_m << ","
          << r.drift[0].reduction << "," << r.drift[1].slamAte_m << "," << r.drift[1].reduction
          << "," << r.drift[0].scaleFreeReduction << "," << r.drift[1].scaleFreeReduction << ","
          << r.devices.devices << "," << r.devices.localized << "," << r.devices.medianError_m
          << "," << r.devices.maxError_m << "," << r.devices.insideShare << "," << r.bearings.count
          << "," << r.bearings.central << "," << r.bearings.centralBeyond30 << ","
          << r.bearings.beyond30 << "," << r.bearings.centralMedian_deg << ","
          << r.bearings.centralBeyond30Unflagged << "," << r.bearingsOfDrive[0].centralBeyond30
          << "," << r.bearingsOfDrive[1].centralBeyond30 << "," << r.noOdoTrackFromTruth_m << ","
          << r.noOdoTrackFromTruthFull_m << "," << r.noOdoSharp3Share;
        for (const auto* perRun : {&r.offlineRuns_m, &r.liveRuns_m, &r.liveLagP99_ms})
            for (int odo = 0; odo < 2; ++odo)
            {
                f << ",\"";
                for (size_t i = 0; i < (*perRun)[odo].size(); ++i)
                    f << (i ? ";" : "") << (*perRun)[odo][i];
                f << "\"";
            }
        f << "," << r.wall_s << ",\"";
        for (const auto& e : r.errors) f << e << ";";
        f << "\"," << r.bearings.centralBeyond30AndAlternatives << ","
          << r.bearings.centralWithin3Sigma << "," << r.bearings.alternativesPerBearing << "\n";
    }
}

/** The kidnapped robot's offline median error with odometry per room (seed), from an earlier
 *  sweep's rooms.csv (none: empty; a room that never converged: ∞). */
std::map<unsigned long, double> offlineOdometryMedians(const fs::path& work)
{
    std::map<unsigned long, double> out;
    const auto file = (work / "rooms.csv").string();
    std::ifstream f(file);
    std::string line;
    if (!std::getline(f, line)) return out;
    const auto header = csvCells(line);
    const size_t cSeed = csvColumn(header, "seed", file),
                 cOdo = csvColumn(header, "offline_odo_median_m", file);
    while (std::getline(f, line))
    {
        const auto c = csvCells(line);
        if (c.size() > std::max(cSeed, cOdo))
            out[std::stoul(c[cSeed])] = std::strtod(c[cOdo].c_str(), nullptr);
    }
    return out;
}

/** --track-from-truth: trackFromTruthOfRoom for every room-N folder of an earlier sweep, a
 *  table of them, the rooms within 0.3 m and (with the sweep's rooms.csv) the rooms whose track
 *  is within 2× of the error with odometry: where it is not, "without odometry ≤ 2× with it"
 *  is beyond the bearings. Returns the exit code (1: no room, or one failed). */
int reportTrackFromTruth(const fs::path& work)
{
    std::vector<std::pair<unsigned long, fs::path>> dirs;
    if (fs::is_directory(work))
        for (const auto& e : fs::directory_iterator(work))
        {
            const auto name = e.path().filename().string();
            if (e.is_directory() && name.rfind("room-", 0) == 0 &&
                name.find_first_not_of("0123456789", 5) == std::string::npos && name.size() > 5)
                dirs.emplace_back(std::stoul(name.substr(5)), e.path());
        }
    if (dirs.empty())
        throw std::invalid_argument(
            "--track-from-truth: no room-N folder in '" + work.string() +
            "' (the --work folder of an earlier run)");
    std::sort(dirs.begin(), dirs.end());
    const auto odometry = offlineOdometryMedians(work);
    std::cout << "# No-odometry track fitted from the true poses: " << work.string() << "\n\n"
              << "Every second from the window smoother's min_window_s on, its track of the last "
                 "track_window_s fitted from the true poses (each room's pf.ini, the recorded "
                 "bearings); error of the newest pose, the one the smoother reports. Full "
                 "windows: only the windows track_window_s long (the steady state, as after a "
                 "filter converged). × odometry: that median over the sweep's kidnapped robot "
                 "offline with odometry (rooms.csv).\n\n"
              << "| room | median [m] | 90 % [m] | windows | full windows: median [m] | × "
                 "odometry |\n|---|---|---|---|---|---|\n";
    size_t within = 0, solved = 0, failed = 0, withinTwice = 0, compared = 0;
    for (const auto& [seed, dir] : dirs)
    {
        std::cerr << "[room " << seed << "] track from the true poses\n";
        try
        {
            const auto t = trackFromTruthOfRoom(dir);
            const auto stats = computeStats(t.newestErrors_m);
            const auto odo = odometry.find(seed);
            // NaN without the sweep's figure, or when it never converged with odometry.
            const double ratio =
                odo != odometry.end() && odo->second > 0 && std::isfinite(odo->second)
                    ? t.fullWindowMedian_m / odo->second
                    : NAN;
            std::cout << "| " << seed << " | " << fmt(t.median_m) << " | "
                      << fmt(stats.count ? stats.p90 : NAN) << " | " << stats.count << " | "
                      << fmt(t.fullWindowMedian_m) << " | " << fmt(ratio, 1) << " |\n";
            if (stats.count) ++solved;
            if (t.median_m <= 0.3) ++within;
            if (!std::isnan(ratio)) ++compared, withinTwice += ratio <= 2 ? 1 : 0;
        }
        catch (const std::exception& ex)
        {
            ++failed;
            std::cerr << "[localization-accuracy] " << dir.string() << ": " << ex.what() << "\n";
        }
    }
    std::cout << "\nRooms whose track from the true poses is within 0.3 m: " << within << " of "
              << solved << (failed ? " (" + std::to_string(failed) + " failed, see above)" : "")
              << "\n";
    if (compared)
        std::cout << "Rooms whose track from the true poses is within 2× of the error with "
                     "odometry: "
                  << withinTwice << " of " << compared
                  << " (full windows; elsewhere \"without odometry ≤ 2× with it\" is beyond what "
                     "the bearings give this track)\n";
    return failed ? 1 : 0;
}

void printReport(const std::vector<Room>& rooms, bool evaluation, const Options& o)
{
    std::cout << "\n# Localization per room: " << rooms.size() << " random rooms ("
              << (evaluation ? "evaluation" : "development") << " seeds " << rooms.front().seed
              << "–" << rooms.back().seed << ")\n\n"
              << "Kidnapped: a " << fmt(o.kidnappedDuration_s, 0) << " s random drive, "
              << o.particles
              << " particles, errors of the estimate (PF mean refined by the window smoother, with "
                 "odometry or without) against the true poses; offline the median of "
              << o.offlineSeeds << " runs with filter seeds 1.." << o.offlineSeeds << ", live of "
              << o.liveSeeds << " (wifi-localize --seed 1.." << o.liveSeeds
              << "; each run's figure in the runs columns, a live run's 99th percentile of the lag "
                 "in parentheses: beyond "
              << fmt(kBehindStream_ms, 0) << " ms it fell behind real time) "
              << "(converged: error < " << fmt(o.convergedThreshold_m, 1) << " m for "
              << fmt(o.convergedHold_s, 0)
              << " s; worst = maximum after convergence). No-odo track from true poses: the "
                 "window smoother's no-odometry track fitted every second from the true poses "
                 "instead of the filter's (its best case), median error of its newest pose (in "
                 "parentheses: over the windows a full track_window_s long); above 0.3 m the "
                 "bearings alone leave the pose open. Drift and devices: "
              << o.laps
              << " laps of a loop; ATE of the solution and of the odometry against the true poses "
                 "(rigid alignment; \"without scale\": a similarity, as the scale of a map with "
                 "estimated APs is the odometry's); devices mapped on the odometry (start at the "
                 "true pose). "
                 "Access points per room: "
              << o.accessPoints
              << (o.apStreams
                      ? ", each sending " + std::to_string(o.apStreams) + " streams from a " +
                            std::to_string(o.apStreams) + "-antenna line"
                      : "")
              << (o.aod ? "; AoA and AoD used, the APs' transmit chains calibrated by "
                          "wifi-calibrate on the first 60 s of the loop drive with its odometry"
                        : "; AoA used")
              << ". Bearings: csi-bearings `default` with the true receiver offsets, both drives "
                 "pooled (the random drive and the loop apart in parentheses); the kidnapped "
                 "runs without odometry use the random drive's bearings estimated with its "
                 "odometry ignored (csi-bearings --no-odometry); live, the same chain run by "
              << (o.liveChain == "sensor" ? "the CSI sensor (its bearing_* keys)" : "wifi-localize")
              << ".\n\n";
    std::cout
        << "| room | size [m] | odo scale / yaw drift | kidnapped offline odo / none [m] "
           "| offline runs odo; none [m] | converge [s] | live odo / none [m] | live runs odo; "
           "none [m] (lag p99 [ms]) | worst after conv. [m] (off odo / none) "
           "| no-odo track from true poses [m] | live in 95 % / 3σ, odo; none | ATE odo [m] "
           "| drift red. known / est. (est. without scale) | device median [m] / in 95 % "
           "| bearings >30° (also beyond 3σ) | >30° and beyond the alternatives (alternatives "
           "per bearing) | within 3σ |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    // Each run's error, and with `lags_ms` its lag p99 in parentheses.
    const auto runsOf =
        [](const std::vector<double>& v, const std::vector<double>* lags_ms = nullptr)
    {
        std::string out;
        for (size_t i = 0; i < v.size(); ++i)
            out += (out.empty() ? "" : " ") + fmt(v[i]) +
                   (lags_ms ? " (" + fmt((*lags_ms)[i], 0) + ")" : "");
        return out.empty() ? std::string("–") : out;
    };
    for (const auto& r : rooms)
    {
        const auto& k = r.kidnapped;
        std::cout << "| " << r.seed << " | " << fmt(r.width, 1) << " × " << fmt(r.depth, 1) << " | "
                  << fmt(100 * r.scaleError, 1) << " % / " << fmt(r.yawDrift_deg_per_m, 2)
                  << "°/m | " << fmt(kidnappedMedian(k[0][0])) << " / "
                  << fmt(kidnappedMedian(k[0][1])) << " | " << runsOf(r.offlineRuns_m[0]) << "; "
                  << runsOf(r.offlineRuns_m[1]) << " | " << fmt(k[0][0].timeToConverge_s, 1)
                  << " / " << fmt(k[0][1].timeToConverge_s, 1) << " | "
                  << fmt(kidnappedMedian(k[1][0])) << " / " << fmt(kidnappedMedian(k[1][1]))
                  << " | " << runsOf(r.liveRuns_m[0], &r.liveLagP99_ms[0]) << "; "
                  << runsOf(r.liveRuns_m[1], &r.liveLagP99_ms[1]) << " | "
                  << fmt(k[0][0].worstAfter_m) << " / " << fmt(k[0][1].worstAfter_m) << " | "
                  << fmt(r.noOdoTrackFromTruth_m) << " (" << fmt(r.noOdoTrackFromTruthFull_m)
                  << ") | " << fmt(100 * k[1][0].inside95After, 0) << " / "
                  << fmt(100 * k[1][0].inside3SigmaAfter, 0) << " %; "
                  << fmt(100 * k[1][1].inside95After, 0) << " / "
                  << fmt(100 * k[1][1].inside3SigmaAfter, 0) << " % | "
                  << fmt(r.drift[0].odometryAte_m) << " | " << fmt(100 * r.drift[0].reduction, 0)
                  << " / " << fmt(100 * r.drift[1].reduction, 0) << " % ("
                  << fmt(100 * r.drift[1].scaleFreeReduction, 0) << " %) | "
                  << fmt(r.devices.medianError_m) << " / " << r.devices.inside << " of "
                  << r.devices.devices << " | " << fmt(100 * r.bearings.centralBeyond30, 1)
                  << " % (" << fmt(100 * r.bearings.centralBeyond30Unflagged, 1) << " %) | "
                  << fmt(100 * r.bearings.centralBeyond30AndAlternatives, 1) << " % ("
                  << fmt(r.bearings.alternativesPerBearing, 2) << ") | "
                  << fmt(100 * r.bearings.centralWithin3Sigma, 1) << " % |\n";
    }
    std::cout << "\n| figure | target per room | rooms meeting it | required | median over rooms | "
                 "worst room |\n|---|---|---|---|---|---|\n";
    const auto ts = targets(o.live);
    std::map<uint32_t, std::vector<std::string>> misses;
    for (const auto& t : ts)
    {
        size_t ok = 0;
        std::vector<double> values;
        double worst = NAN;
        uint32_t worstSeed = 0;
        const bool lowerIsBetter = t.pass(-1e9);
        for (const auto& r : rooms)
        {
            const double v = t.value(r);
            if (passes(t, r))
                ++ok;
            else
                misses[r.seed].push_back(t.figure + " " + fmt(v, t.digits));
            if (std::isnan(v)) continue;
            values.push_back(v);
            if (std::isnan(worst) || (lowerIsBetter ? v > worst : v < worst))
                worst = v, worstSeed = r.seed;
        }
        const double share = double(ok) / double(rooms.size());
        std::cout << "| " << t.figure << " | " << t.target << " | " << ok << " / " << rooms.size()
                  << " (" << fmt(100 * share, 0) << " %) " << (share >= t.requiredShare ? "✓" : "✗")
                  << " | " << (t.requiredShare >= 1 ? "every room" : "≥ 90 %") << " | "
                  << (values.empty() ? "–" : fmt(medianOf(values), t.digits)) << " | "
                  << fmt(worst, t.digits) << " (" << worstSeed << ") |\n";
    }
    // Worst rooms: most missed targets first.
    std::vector<const Room*> order;
    for (const auto& r : rooms)
        if (misses.count(r.seed)) order.push_back(&r);
    std::stable_sort(
        order.begin(), order.end(),
        [&](const Room* a, const Room* b)
        { return misses[a->seed].size() > misses[b->seed].size(); });
    std::cout << "\n## Rooms that miss a target (" << order.size() << " of " << rooms.size()
              << "), worst first\n\n";
    for (const Room* r : order)
    {
        std::cout << "- room " << r->seed << " (" << fmt(r->width, 1) << " × " << fmt(r->depth, 1)
                  << " m): misses ";
        for (size_t i = 0; i < misses[r->seed].size(); ++i)
            std::cout << (i ? "; " : "") << misses[r->seed][i];
        std::cout << ".\n  Why: " << whyItFails(*r, ts) << ".\n  Pictures: "
                  << (o.work / ("room-" + std::to_string(r->seed)) /
                      ("room-" + std::to_string(r->seed) + "-{kidnapped,loop}.png"))
                         .string()
                  << "\n";
        drawRoom(*r, o.work / ("room-" + std::to_string(r->seed)));
    }
}
}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "localization-accuracy",
        [&]
        {
            TCLAP::CmdLine cmd(
                "The three localization case studies (kidnapped robot offline and live, with and "
                "without odometry; drift correction with known and estimated APs; device mapping "
                "from odometry) and the bearings, each judged per random room "
                "(sim::randomRoomYaml): prints a table per room, the share of rooms meeting "
                "each target of issue 19 and the rooms that miss one, with pictures. Seeds < "
                "1000 are for development, >= 1000 (--eval) for evaluation.",
                ' ', "0.1");
            TCLAP::ValueArg<unsigned> argRooms("", "rooms", "Number of rooms", false, 0, "N", cmd);
            TCLAP::SwitchArg argEval(
                "", "eval", "Evaluation rooms (seeds from 1000); default: development (from 1)",
                cmd);
            TCLAP::ValueArg<uint32_t> argFirst(
                "", "first-seed", "First room seed (default 1, with --eval 1000)", false, 0, "SEED",
                cmd);
            TCLAP::ValueArg<std::string> argWork(
                "w", "work", "Folder for every room's data, the CSV and the pictures", false,
                "localization-accuracy", "DIR", cmd);
            TCLAP::ValueArg<std::string> argCsv(
                "", "csv", "Per-room CSV (default WORK/rooms.csv)", false, "", "FILE", cmd);
            TCLAP::ValueArg<double> argDuration(
                "d", "duration", "Kidnapped drive (and each live run) [s]", false, 40, "S", cmd);
            TCLAP::ValueArg<unsigned> argLaps(
                "", "laps", "Laps of the drift-correction loop", false, 3, "N", cmd);
            TCLAP::ValueArg<int> argParticles(
                "n", "particles", "Particles of the kidnapped-robot filters", false, 3000, "N",
                cmd);
            TCLAP::ValueArg<int> argOfflineSeeds(
                "", "offline-seeds",
                "Filter seeds of each offline kidnapped run; the room's figure is the median run",
                false, 3, "N", cmd);
            TCLAP::ValueArg<int> argLiveSeeds(
                "", "live-seeds",
                "Filter seeds of each live kidnapped run (wifi-localize --seed; each takes the "
                "drive's duration); the room's figure is the median run",
                false, 3, "N", cmd);
            TCLAP::SwitchArg argNoLive(
                "", "no-live",
                "Skip the live runs (each takes the drive's duration: twice --live-seeds)", cmd);
            std::vector<std::string> chains = {"app", "sensor"};
            TCLAP::ValuesConstraint<std::string> chainNames(chains);
            TCLAP::ValueArg<std::string> argLiveChain(
                "", "live-chain",
                "Live bearings from wifi-localize's own chain (app) or the CSI sensor's "
                "(sensor: its bearing_* keys; wifi-localize hands it the odometry)",
                false, "app", &chainNames, cmd);
            TCLAP::ValueArg<int> argAps(
                "", "aps",
                "Access points per room (the first three are the seed's whatever the count)", false,
                3, "N", cmd);
            TCLAP::ValueArg<int> argApStreams(
                "", "ap-streams",
                "Streams every AP sends, from a line of as many antennas (ap-linear-N.yaml): 2 or "
                "4; default: one or two, drawn per AP (the rooms and drives stay the seed's)",
                false, 0, "N", cmd);
            TCLAP::SwitchArg argAod(
                "", "aod",
                "AoD as well as AoA in every estimator, the APs' transmit chains calibrated by "
                "wifi-calibrate --transmit-chains on the first 60 s of the loop drive with its "
                "odometry (needs --ap-streams)",
                cmd);
            TCLAP::ValueArg<std::string> argTrackFromTruth(
                "", "track-from-truth",
                "Run no room: for each room-N folder of an earlier --work DIR, the window "
                "smoother's no-odometry track fitted from the true poses (its best case; above "
                "0.3 m the bearings alone leave the pose open)",
                false, "", "DIR", cmd);
            if (const int rc = cli::parseCommandLine(cmd, argc, const_cast<const char**>(argv));
                rc >= 0)
                return rc;
            if (argTrackFromTruth.isSet())
            {
                if (argRooms.isSet())
                    throw std::invalid_argument("--track-from-truth runs no room: no --rooms");
                return reportTrackFromTruth(argTrackFromTruth.getValue());
            }
            if (argRooms.getValue() == 0) throw std::invalid_argument("--rooms must be > 0");
            const bool evaluation = argEval.getValue();
            const uint32_t first = argFirst.isSet() ? argFirst.getValue()
                                   : evaluation     ? sim::kFirstEvaluationSeed
                                                    : 1u;
            if (first == 0) throw std::invalid_argument("--first-seed: seeds start at 1");
            if (sim::isEvaluationSeed(first) != evaluation ||
                sim::isEvaluationSeed(first + argRooms.getValue() - 1) != evaluation)
                throw std::invalid_argument(
                    std::string("--first-seed: ") +
                    (evaluation ? "evaluation seeds are >= 1000"
                                : "development seeds are < 1000 (--eval for the others)"));
            Options o;
            o.work = fs::absolute(argWork.getValue());
            o.kidnappedDuration_s = argDuration.getValue();
            o.laps = argLaps.getValue();
            o.particles = argParticles.getValue();
            o.offlineSeeds = argOfflineSeeds.getValue();
            if (o.offlineSeeds < 1) throw std::invalid_argument("--offline-seeds >= 1");
            o.liveSeeds = argLiveSeeds.getValue();
            if (o.liveSeeds < 1) throw std::invalid_argument("--live-seeds >= 1");
            o.live = !argNoLive.getValue();
            o.liveChain = argLiveChain.getValue();
            o.accessPoints = argAps.getValue();
            o.apStreams = argApStreams.getValue();
            o.aod = argAod.getValue();
            if (o.apStreams != 0 && o.apStreams != 2 && o.apStreams != 4)
                throw std::invalid_argument("--ap-streams: 2 or 4");
            if (o.aod && o.apStreams == 0)
                throw std::invalid_argument("--aod needs --ap-streams 2 or 4 (every AP an array)");
            if (o.accessPoints < 3) throw std::invalid_argument("--aps >= 3");
            if (!(o.kidnappedDuration_s >= 10)) throw std::invalid_argument("--duration >= 10 s");
            if (o.laps < 2) throw std::invalid_argument("--laps >= 2 (revisits)");
            fs::create_directories(o.work);

            std::vector<Room> rooms;
            for (unsigned i = 0; i < argRooms.getValue(); ++i)
            {
                rooms.push_back(evaluateRoom(first + i, o));
                const auto& r = rooms.back();
                std::cerr << " — " << fmt(r.wall_s, 0) << " s (room " << i + 1 << " of "
                          << argRooms.getValue() << "): kidnapped offline "
                          << fmt(kidnappedMedian(r.kidnapped[0][0])) << " / "
                          << fmt(kidnappedMedian(r.kidnapped[0][1])) << " m, live "
                          << fmt(kidnappedMedian(r.kidnapped[1][0])) << " / "
                          << fmt(kidnappedMedian(r.kidnapped[1][1])) << " m, drift "
                          << fmt(100 * r.drift[0].reduction, 0) << " / "
                          << fmt(100 * r.drift[1].reduction, 0) << " %, devices "
                          << fmt(r.devices.medianError_m) << " m, bearings >30° "
                          << fmt(100 * r.bearings.centralBeyond30, 1) << " %\n";
                writeCsv(
                    rooms, argCsv.isSet() ? argCsv.getValue() : (o.work / "rooms.csv").string());
            }
            printReport(rooms, evaluation, o);
            size_t failedPrograms = 0;
            for (const auto& r : rooms) failedPrograms += r.errors.size();
            if (failedPrograms)
                std::cout << "\n" << failedPrograms << " program run(s) failed (see above)\n";
            return failedPrograms ? 2 : 0;
        });
}
