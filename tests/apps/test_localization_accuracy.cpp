/* mrpt_wifi — a small slice of the per-room localization evaluation (localization-accuracy):
 * one development room, short drives, every case study end to end (simulator, csi-bearings,
 * the offline and live filters, graph SLAM, device map), its figures within generous bounds.
 * The full sweep is a command (share/localization/README.md, "Per-room evaluation"). */
#include <gtest/gtest.h>
#include <mrpt/core/bits_math.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/BearingRecord.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <map>
#include <sstream>

#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

namespace
{
/** rooms.csv as column name → value of each row. */
std::vector<std::map<std::string, std::string>> readRoomsCsv(const std::string& path)
{
    std::istringstream in(test::readFile(path));
    std::vector<std::string> header;
    std::vector<std::map<std::string, std::string>> rows;
    for (std::string line; std::getline(in, line);)
    {
        std::vector<std::string> cells;
        std::istringstream s(line);
        for (std::string c; std::getline(s, c, ',');) cells.push_back(c);
        if (header.empty())
        {
            header = cells;
            continue;
        }
        auto& row = rows.emplace_back();
        for (size_t i = 0; i < cells.size() && i < header.size(); ++i) row[header[i]] = cells[i];
    }
    return rows;
}

double number(const std::map<std::string, std::string>& row, const std::string& column)
{
    const auto it = row.find(column);
    if (it == row.end()) return NAN;
    try
    {
        return std::stod(it->second);
    }
    catch (const std::exception&)
    {
        return NAN;
    }
}
}  // namespace

TEST(LocalizationAccuracy, EvaluatesOneRoomEndToEnd)
{
    // The sweep's 40 s drive: with [OdometryMotion] this room's filter converges 12-24 s after
    // the start (1000 particles, 3 seeds), so a 20 s drive ended before it had.
    test::TempDir tmp;
    const auto r = test::run(
        test::binDir() +
        "/localization-accuracy --rooms 1 --first-seed 7 -d 40 --laps 2 -n 1000 --live-seeds 1 "
        "-w " +
        tmp.file("work"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    // Progress per room, the per-room table, the targets and the list of rooms that miss one.
    EXPECT_NE(r.output.find("[room 7]"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("| figure | target per room |"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("## Rooms that miss a target"), std::string::npos) << r.output;

    const auto rows = readRoomsCsv(tmp.file("work/rooms.csv"));
    ASSERT_EQ(rows.size(), 1u);
    const auto& room = rows.front();
    EXPECT_EQ(number(room, "seed"), 7);
    // Every run produced its figure, and each is where a working chain puts it (the sweep's
    // targets are tighter; these bounds catch a broken chain, not a small regression).
    EXPECT_LE(number(room, "offline_odo_median_m"), 1.0) << r.output;
    EXPECT_TRUE(std::isfinite(number(room, "offline_noodo_worst_all_m"))) << r.output;
    // Offline, three filter seeds per run (the default): the room's figure is their median;
    // live one (--live-seeds 1, to keep the suite's wall time: each live run is real time).
    const auto perRun = [&](const std::string& column)
    {
        std::string cell = room.at(column);
        cell.erase(std::remove(cell.begin(), cell.end(), '"'), cell.end());
        std::vector<double> runs;
        std::istringstream s(cell);
        for (std::string v; std::getline(s, v, ';');) runs.push_back(std::stod(v));
        return runs;
    };
    for (const std::string kind : {"offline", "live"})
        for (const std::string run : {"odo", "noodo"})
        {
            auto runs = perRun(kind + "_" + run + "_runs_m");
            ASSERT_EQ(runs.size(), kind == "offline" ? 3u : 1u) << kind << " " << run;
            std::sort(runs.begin(), runs.end());
            EXPECT_DOUBLE_EQ(
                runs[kind == "offline" ? 1 : 0], number(room, kind + "_" + run + "_median_m"))
                << kind << " " << run;
        }
    // Each live run's lag, from its wifi-localize summary: known, and a run can't be ahead of
    // its own bearings.
    for (const std::string run : {"odo", "noodo"})
    {
        const auto lags = perRun("live_" + run + "_lag_p99_ms");
        ASSERT_EQ(lags.size(), 1u) << run;
        for (const double lag : lags) EXPECT_GE(lag, 0.0) << run;
    }
    EXPECT_TRUE(
        std::filesystem::exists(tmp.file("work/room-7/pf-odometry-seed3/estimate_tum.txt")));
    EXPECT_TRUE(std::filesystem::exists(tmp.file("work/room-7/live-no-odometry/estimate_tum.txt")));
    // Live runs on the wall clock (a busy machine batches more bearings per filter step): only
    // that both ran on the streamed room and, with odometry, stayed near it (7.1 × 7.7 m).
    EXPECT_LE(number(room, "live_odo_worst_all_m"), 10.0) << r.output;
    EXPECT_TRUE(std::isfinite(number(room, "live_noodo_worst_all_m"))) << r.output;
    // Both kinds of run get the drive from its first frame (the emulator streams once
    // wifi-localize listens), so live and offline are compared on the same bearings. The
    // first frame is a few ms into the drive; a live run started after the stream had begun
    // missed 0.35-0.55 s of it.
    for (const char* run : {"offline_odo", "offline_noodo", "live_odo", "live_noodo"})
        EXPECT_LT(number(room, std::string(run) + "_start_s"), 0.1) << run << "\n" << r.output;
    // The live filter's reported uncertainty is judged against its error once it converged
    // (a zero or missing covariance would put nearly every error outside its ellipse).
    if (std::isfinite(number(room, "live_odo_median_m")))
    {
        EXPECT_GE(number(room, "live_odo_inside95_after"), 0.5) << r.output;
        // Within 3σ (Mahalanobis distance 3) holds every error inside the 95 % ellipse (2.45).
        EXPECT_GE(
            number(room, "live_odo_inside3sigma_after"), number(room, "live_odo_inside95_after"))
            << r.output;
    }
    EXPECT_GE(number(room, "reduction_known"), 0.3) << r.output;
    EXPECT_TRUE(std::isfinite(number(room, "reduction_estimated"))) << r.output;
    // With the unobservable scale taken out, the bearings' correction of estimated APs shows.
    EXPECT_GE(number(room, "reduction_estimated_scale_free"), 0.3) << r.output;
    EXPECT_EQ(number(room, "devices"), 3) << r.output;
    EXPECT_LE(number(room, "device_median_m"), 1.0) << r.output;
    EXPECT_GT(number(room, "bearings"), 1000) << r.output;
    EXPECT_LE(number(room, "central_beyond30"), 0.15) << r.output;
    EXPECT_LE(number(room, "central_beyond30_unflagged"), number(room, "central_beyond30"))
        << r.output;
    EXPECT_EQ(room.at("failed_programs"), "\"\"") << r.output;
    // The runs without odometry take bearings estimated without it: the same frames, other
    // windows while the robot turns.
    const auto withOdo =
        readBearingCsv(tmp.file("work/room-7/kidnapped/bearings.csv"), BearingCsvOptions());
    const auto withoutOdo = readBearingCsv(
        tmp.file("work/room-7/kidnapped/bearings-no-odometry.csv"), BearingCsvOptions());
    EXPECT_EQ(withoutOdo.size(), withOdo.size());
    size_t differ = 0;
    for (size_t i = 0; i < std::min(withOdo.size(), withoutOdo.size()); ++i)
        differ += withOdo[i].aoa != withoutOdo[i].aoa;
    EXPECT_GT(differ, 0u);
    // How often those bearings fixed a pose on their own (3+ APs sharp in a second), as
    // wifi-pf-localization's summary rounds it.
    EXPECT_NEAR(
        number(room, "noodo_sharp3_seconds"),
        sharpCoverage(withoutOdo, BearingUse{}, mrpt::DEG2RAD(10.0)).shareWithAtLeast(3), 0.006)
        << r.output;
    // The no-odometry track fitted from the true poses (its best case), in the CSV and again
    // from the recorded room alone.
    const double fromTruth = number(room, "noodo_track_from_truth_m");
    EXPECT_TRUE(std::isfinite(fromTruth)) << r.output;
    const auto again =
        test::run(test::binDir() + "/localization-accuracy --track-from-truth " + tmp.file("work"));
    ASSERT_EQ(again.exitCode, 0) << again.output;
    std::ostringstream row;
    row << "| 7 | " << std::fixed << std::setprecision(2) << fromTruth << " |";
    const auto at = again.output.find(row.str());
    ASSERT_NE(at, std::string::npos) << again.output;
    EXPECT_NE(again.output.find("within 0.3 m: "), std::string::npos) << again.output;
    // ... and against the sweep's error with odometry (its rooms.csv): the row ends with the
    // ratio of the full windows' median to it, and the rooms within 2× are counted.
    std::ostringstream ratio;
    ratio << "| " << std::fixed << std::setprecision(1)
          << number(room, "noodo_track_full_windows_m") / number(room, "offline_odo_median_m")
          << " |\n";
    const auto line = again.output.substr(at, again.output.find('\n', at) - at + 1);
    EXPECT_GE(line.size(), ratio.str().size());
    EXPECT_EQ(line.substr(line.size() - std::min(line.size(), ratio.str().size())), ratio.str())
        << line;
    EXPECT_NE(again.output.find("within 2× of the error with odometry: "), std::string::npos)
        << again.output;
}

TEST(LocalizationAccuracy, WithAodCalibratesEveryApAndUsesItsAod)
{
    // --ap-streams 4 --aod: every AP a 4-antenna line, its transmit chains calibrated from the
    // loop drive's odometry (wifi-calibrate), AoD in the offline and graph-SLAM bearings. One
    // filter seed and no live runs (wifi-localize with AoD from the emulator:
    // WifiLocalize.UsesTheCsiSensorsOwnLiveBearings), for the suite's wall time.
    test::TempDir tmp;
    const auto r = test::run(
        test::binDir() +
        "/localization-accuracy --rooms 1 --first-seed 7 -d 20 --laps 2 -n 1000 --ap-streams 4 "
        "--aod --offline-seeds 1 --no-live -w " +
        tmp.file("work"));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("4-antenna line"), std::string::npos) << r.output;
    const auto rows = readRoomsCsv(tmp.file("work/rooms.csv"));
    ASSERT_EQ(rows.size(), 1u);
    const auto& room = rows.front();
    EXPECT_EQ(room.at("failed_programs"), "\"\"") << r.output;
    // One calibration per AP, beside the receiver's.
    size_t calibrated = 0;
    for (const auto& e :
         std::filesystem::directory_iterator(tmp.file("work/room-7/calib/transmitters")))
        calibrated += e.is_directory();
    EXPECT_EQ(calibrated, 3u);
    // Every AP's bearings carry AoD.
    std::map<std::string, size_t> withAod;
    for (const auto& b :
         readBearingCsv(tmp.file("work/room-7/kidnapped/bearings.csv"), BearingCsvOptions()))
        if (b.hasAod) ++withAod[b.transmitter.asString()];
    EXPECT_EQ(withAod.size(), 3u);
    for (const auto& [mac, n] : withAod) EXPECT_GT(n, 100u) << mac;
    EXPECT_NE(
        test::readFile(tmp.file("work/room-7/pf.ini")).find("use_aod = true"), std::string::npos);
    EXPECT_LE(number(room, "offline_odo_median_m"), 1.0) << r.output;
    EXPECT_GE(number(room, "reduction_known"), 0.3) << r.output;
}

TEST(LocalizationAccuracy, BadArgumentsAreNamedWithoutRunningARoom)
{
    test::TempDir tmp;
    const auto fewAps = test::run(
        test::binDir() + "/localization-accuracy --rooms 1 --aps 2 -w " + tmp.file("work"));
    EXPECT_NE(fewAps.exitCode, 0);
    EXPECT_NE(fewAps.output.find("--aps"), std::string::npos) << fewAps.output;
    const auto evalSeed = test::run(
        test::binDir() + "/localization-accuracy --rooms 1 --first-seed 1000 -w " +
        tmp.file("work"));
    EXPECT_NE(evalSeed.exitCode, 0);
    EXPECT_NE(evalSeed.output.find("--first-seed"), std::string::npos) << evalSeed.output;
    const auto chain = test::run(
        test::binDir() + "/localization-accuracy --rooms 1 --live-chain router -w " +
        tmp.file("work"));
    EXPECT_NE(chain.exitCode, 0);
    EXPECT_NE(chain.output.find("--live-chain"), std::string::npos) << chain.output;
    EXPECT_FALSE(std::filesystem::exists(tmp.file("work/room-1"))) << fewAps.output;
    // Re-analysis of a folder that holds no room, and with a room count, names the option.
    const auto noRooms = test::run(
        test::binDir() + "/localization-accuracy --track-from-truth " + tmp.file("nothing"));
    EXPECT_NE(noRooms.exitCode, 0);
    EXPECT_NE(noRooms.output.find("--track-from-truth"), std::string::npos) << noRooms.output;
    EXPECT_NE(noRooms.output.find(tmp.file("nothing")), std::string::npos) << noRooms.output;
    const auto both = test::run(
        test::binDir() + "/localization-accuracy --rooms 1 --track-from-truth " + tmp.file("w"));
    EXPECT_NE(both.exitCode, 0);
    EXPECT_NE(both.output.find("--rooms"), std::string::npos) << both.output;
    for (const char* args : {"--ap-streams 3", "--aod", "--live-seeds 0", "--offline-seeds 0"})
    {
        const auto bad = test::run(
            test::binDir() + "/localization-accuracy --rooms 1 " + args + " -w " +
            tmp.file("work"));
        EXPECT_NE(bad.exitCode, 0) << args;
        EXPECT_NE(bad.output.find(std::string(args).substr(0, 6)), std::string::npos) << bad.output;
    }
}
