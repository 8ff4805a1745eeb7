/* Bearing accuracy against the simulator's ground truth (issue 5 targets). The simulator's true
 * per-chain offsets stand in for a calibration (the calibration tool is another issue). */
#include <gtest/gtest.h>

#include "BearingAccuracy.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::test;

namespace
{
AccuracyDataset dataset(const std::string& scenario, Environment env, double snr, bool calibrated)
{
    AccuracyCase c;
    c.scenarioFile = scenarioPath(scenario);
    c.environment = env;
    c.snr_dB = snr;
    c.calibrated = calibrated;
    c.estimates = 150;
    return makeDataset(c);
}

void record(const AccuracyStats& s, const std::string& tag)
{
    ::testing::Test::RecordProperty(
        tag + "_" + s.algorithm + "_median_deg", std::to_string(s.median_deg));
    ::testing::Test::RecordProperty(
        tag + "_" + s.algorithm + "_p90_deg", std::to_string(s.p90_deg));
}
}  // namespace

TEST(BearingAccuracy, CalibratedModerateMultipathBestMedianWithinTwoDegrees)
{
    const auto d = dataset("bearing", Environment::Moderate, 20, true);
    double best = INFINITY;
    std::string bestName;
    for (const auto& n : bearing::arrayEstimatorNames())
    {
        const AccuracyStats s = evaluate(d, n);
        ASSERT_GE(s.count, 140u) << n;
        record(s, "moderate20");
        std::cout << n << ": median " << s.median_deg << " p90 " << s.p90_deg << " deg\n";
        if (s.median_deg < best) best = s.median_deg, bestName = n;
    }
    std::cout << "best: " << bestName << " " << best << " deg\n";
    EXPECT_LE(best, 2.0);
}

TEST(BearingAccuracy, LineOfSightWithinTwiceTheCramerRaoBound)
{
    for (double snr : {10.0, 20.0, 30.0})
    {
        const auto d = dataset("bearing", Environment::LineOfSight, snr, true);
        for (const char* algo : {"aoa_only", "music", "fft"})
        {
            const AccuracyStats s = evaluate(d, algo);
            std::cout << algo << " @" << snr << " dB: median " << s.median_deg << " CRB "
                      << s.crbMedian_deg << " err/CRB(±60°) " << s.errorOverCrbRmsCentral
                      << " over " << s.centralCount << "\n";
            ASSERT_GE(s.centralCount, 50u);
            EXPECT_LE(s.errorOverCrbRmsCentral, 2.0) << algo << " at " << snr << " dB";
        }
    }
}

TEST(BearingAccuracy, ReportedSigmaCoversTheErrors)
{
    for (Environment env : {Environment::LineOfSight, Environment::Moderate})
    {
        const auto d = dataset("bearing", env, 20, true);
        for (const char* algo : {"aoa_only", "fft", "spotfi"})
        {
            const AccuracyStats s = evaluate(d, algo);
            EXPECT_GE(s.withinThreeSigma, 0.8) << algo << " in " << toString(env);
        }
    }
}

TEST(BearingAccuracy, UncalibratedIsFarWorseForTheRecord)
{
    const auto d = dataset("bearing", Environment::Moderate, 20, false);
    double best = INFINITY;
    for (const auto& n : bearing::arrayEstimatorNames())
        best = std::min(best, evaluate(d, n).median_deg);
    std::cout << "uncalibrated best median " << best << " deg\n";
    EXPECT_GT(best, 10.0);
}

TEST(BearingAccuracy, AngleOfDepartureOnTheKidnappedScenario)
{
    const auto params = mrpt::containers::yaml::FromText("window: 4");
    const AccuracyStats los =
        evaluate(dataset("kidnapped", Environment::LineOfSight, 20, true), "aod", params);
    const AccuracyStats mp =
        evaluate(dataset("kidnapped", Environment::Moderate, 20, true), "aod", params);
    std::cout << "AoD LoS median " << los.aodMedian_deg << ", multipath median " << mp.aodMedian_deg
              << " p90 " << mp.aodP90_deg << "\n";
    EXPECT_GE(los.aodCount, 140u);
    EXPECT_LE(los.aodMedian_deg, 0.5);
    EXPECT_LE(mp.aodMedian_deg, 5.0);
}

// ---- Random rooms, evaluation seeds (never tuned on): honest σ and the default estimator.
namespace
{
std::vector<ErrorRecord> roomErrors(
    const std::string& algo, Environment env, double snr, unsigned rooms = 2)
{
    std::vector<ErrorRecord> recs;
    for (uint32_t seed : roomSeeds(true, rooms))
    {
        AccuracyCase c;
        c.environment = env;
        c.snr_dB = snr;
        c.estimates = 90;
        collectErrors(makeRandomRoomDataset(c, seed), algo, recs);
    }
    return recs;
}
}  // namespace

TEST(BearingAccuracyRooms, ReportedSigmaPredictsTheError)
{
    for (Environment env : {Environment::LineOfSight, Environment::Moderate})
        for (double snr : {10.0, 30.0})
            for (const char* algo : {"default", "svd", "fft", "spotfi", "aoa_only"})
            {
                const RoomStats s = summarize(roomErrors(algo, env, snr));
                std::cout << algo << " " << toString(env) << " " << snr << " dB: ≤2σ "
                          << s.withinTwoSigma << " ≤3σ " << s.withinThreeSigma << " median σ "
                          << s.medianStd_deg << "\n";
                ASSERT_GE(s.count, 170u) << algo;
                EXPECT_GE(s.withinThreeSigma, 0.95) << algo << " " << toString(env) << " " << snr;
                EXPECT_GE(s.withinTwoSigma, 0.80) << algo << " " << toString(env) << " " << snr;
            }
}

TEST(BearingAccuracyRooms, DefaultEstimatorBeatsTheMatchedFilterInMultipath)
{
    const RoomStats d = summarize(roomErrors("default", Environment::Moderate, 25, 3));
    const RoomStats f = summarize(roomErrors("fft", Environment::Moderate, 25, 3));
    std::cout << "default: median " << d.centralMedian_deg << " p90 " << d.centralP90_deg
              << " >30° " << d.centralBeyond30 << " (all " << d.beyond30 << ")\nfft: median "
              << f.centralMedian_deg << " p90 " << f.centralP90_deg << " >30° " << f.centralBeyond30
              << " (all " << f.beyond30 << ")\n";
    EXPECT_LE(d.centralMedian_deg, 1.5);
    EXPECT_LE(d.centralP90_deg, 8.0);
    EXPECT_LT(d.centralMedian_deg, f.centralMedian_deg);
    EXPECT_LE(d.centralBeyond30, f.centralBeyond30);
    EXPECT_LE(d.beyond30, 0.10);
}

// ---- Whole streams through BearingProcessor (per-transmitter tracking sees the stream).
namespace
{
RoomStats streamStats(std::optional<bool> tracking)
{
    StreamCase c;
    c.base.environment = Environment::Moderate;
    c.base.snr_dB = 25;
    c.duration_s = 20;
    c.tracking = tracking;
    std::vector<ErrorRecord> all;
    for (uint32_t seed : roomSeeds(true, 3))
    {
        std::map<std::string, std::vector<ErrorRecord>> recs;
        streamErrors(c, seed, {"default"}, mrpt::containers::yaml::Map(), recs);
        all.insert(all.end(), recs["default"].begin(), recs["default"].end());
    }
    return summarize(all);
}
}  // namespace

TEST(BearingAccuracyStream, TrackingKeepsEndfireAliasesRare)
{
    // Evaluation rooms 1000–1002, first 20 s, true poses: measured 1.9 % of all bearings
    // beyond 30° with tracking (the default; 2.9 % with the tracker before 2026-11-28), 3.8 %
    // without.
    const RoomStats on = streamStats(std::nullopt);
    const RoomStats off = streamStats(false);
    std::cout << "tracking on: >30° all " << on.beyond30 << " central " << on.centralBeyond30
              << " median " << on.centralMedian_deg << " ≤3σ " << on.withinThreeSigma
              << "\ntracking off: >30° all " << off.beyond30 << " central " << off.centralBeyond30
              << "\n";
    ASSERT_GE(on.count, 1000u);
    EXPECT_LE(on.beyond30, 0.035);  // without tracking 3.8 %: this fails
    EXPECT_LT(on.beyond30, off.beyond30);
    EXPECT_LE(on.centralMedian_deg, 1.5);
    EXPECT_GE(on.withinThreeSigma, 0.95);
    EXPECT_GE(on.withinTwoSigma, 0.80);
}
