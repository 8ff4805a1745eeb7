/* Issue 54: bearing accuracy on real RT-AC86U captures with ground truth (muTrack D1, in
 * ../shared/data/mutrack; skips without it). Each (trace, AP) pcap goes through the shipped
 * `default` chain (BearingProcessor, no odometry) with the array naming cores 0, 1, 3 and the
 * splitter calibration of the README; the figures are compared with bounds a little looser than
 * what was measured when the estimators were fixed (scripts/mutrack-eval.sh prints the same
 * figures from the command-line programs). */
#include <gtest/gtest.h>
#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/obs/PhaseCalibration.h>
#include <mrpt_wifi/obs/bearing/BearingProcessor.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

#include "SyntheticCsi.h"
#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
// Bounds a little looser than measured on 2026-11-29 over all 48 pairs of D1 (per-trace
// median |error| 7.85 deg, 9 of 48 pairs beyond 20 deg, per packet median 8.27 deg, 7.6 % beyond
// 30 deg, 96.2 % within 3 sigma; before issue 54's changes 8.28 deg, 25.0 %, 8.57 deg, 10.2 %,
// 87.4 %). The same run from the command-line programs: scripts/mutrack-eval.sh.
constexpr double kMaxTraceMedian_deg = 8.2;
constexpr double kMaxBeyond20_pct = 21.0;  // 10 of 48 pairs
constexpr double kMaxPacketMedian_deg = 9.0;
constexpr double kMaxPacketBeyond30_pct = 9.0;
constexpr double kMinWithin3Sigma_pct = 94.0;
constexpr char kArray[] = "rt-ac86u-3core-57mm";  // cores 0, 1, 3

struct TruthRow
{
    std::string file;
    int ap = 0, trace = 0;
    double expected_deg = 0;
};

std::vector<TruthRow> readTruth(const std::string& path)
{
    std::ifstream in(path);
    std::string line;
    std::getline(in, line);  // header: file,device,ap,trace,...,expected_aoa_deg
    std::vector<TruthRow> rows;
    while (std::getline(in, line))
    {
        std::vector<std::string> cells;
        std::stringstream ss(line);
        for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
        if (cells.size() < 10) continue;
        rows.push_back({cells[0], std::stoi(cells[2]), std::stoi(cells[3]), std::stod(cells[9])});
    }
    return rows;
}

/** The splitter calibration the README gives (core 1 − core 0, core 3 − core 0 at k = −2;
 *  flat across subcarriers), per AP, for the array's elements (cores 0, 1, 3). */
PhaseCalibration splitterCalibration(int ap, const std::string& device)
{
    static const std::map<int, std::pair<double, double>> phases = {
        {2, {2.8312, 2.7790}}, {3, {-2.6780, 0.5276}}, {5, {3.1189, 3.0228}}};
    PhaseCalibration c;
    c.device = device;
    c.chanspec = Chanspec::make(6, 20);
    c.method = "README splitter phases";
    c.subcarriers = {-28, 28};
    const auto [p1, p3] = phases.at(ap);
    c.phases_rad = {{0.0, 0.0}, {p1, p1}, {p3, p3}};
    return c;
}

double median(std::vector<double> v)
{
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct PairResult
{
    TruthRow truth;
    std::vector<double> aoa_deg, std_deg;
    double traceError_deg = 180;  //!< |median bearing − truth|; 180 without bearings
};

struct Figures
{
    std::vector<PairResult> pairs;
    double traceMedian_deg = NAN, beyond20_pct = NAN;
    double packetMedian_deg = NAN, packetBeyond30_pct = NAN, packetWithin3Sigma_pct = NAN;
};

Figures run(const std::vector<TruthRow>& rows, const std::string& dataDir)
{
    const AntennaArray array = test::loadArray(kArray);
    Figures out;
    for (const auto& row : rows)
    {
        CsiPreprocessor pre(
            PreprocessOptions(), array,
            CalibrationStore::fromCalibration(splitterCalibration(row.ap, array.name)));
        bearing::BearingProcessor processor(
            std::move(pre), bearing::createEstimator("default"),
            bearing::BearingProcessor::Options());
        PairResult p;
        p.truth = row;
        readCsiFrames(
            dataDir + "/" + row.file, {},
            [&](CObservationWiFiCSI::Ptr&& f)
            {
                if (auto b = processor.process(*f))
                {
                    p.aoa_deg.push_back(b->aoa_rad * 180 / M_PI);
                    p.std_deg.push_back(b->aoaStd_rad * 180 / M_PI);
                }
            });
        if (!p.aoa_deg.empty()) p.traceError_deg = std::abs(median(p.aoa_deg) - row.expected_deg);
        out.pairs.push_back(std::move(p));
    }
    std::vector<double> traceErr, packetErr;
    size_t beyond20 = 0, beyond30 = 0, within3 = 0;
    for (const auto& p : out.pairs)
    {
        traceErr.push_back(p.traceError_deg);
        beyond20 += p.traceError_deg > 20;
        for (size_t i = 0; i < p.aoa_deg.size(); ++i)
        {
            const double e = std::abs(p.aoa_deg[i] - p.truth.expected_deg);
            packetErr.push_back(e);
            beyond30 += e > 30;
            within3 += e <= 3 * p.std_deg[i];
        }
    }
    out.traceMedian_deg = median(traceErr);
    out.beyond20_pct = 100.0 * double(beyond20) / double(traceErr.size());
    out.packetMedian_deg = median(packetErr);
    out.packetBeyond30_pct = 100.0 * double(beyond30) / double(packetErr.size());
    out.packetWithin3Sigma_pct = 100.0 * double(within3) / double(packetErr.size());
    return out;
}

std::string describe(const Figures& f)
{
    std::ostringstream o;
    o << "per-trace median |error| " << f.traceMedian_deg << " deg, beyond 20 deg "
      << f.beyond20_pct << " %; per packet median " << f.packetMedian_deg << " deg, beyond 30 "
      << f.packetBeyond30_pct << " %, within 3 sigma " << f.packetWithin3Sigma_pct << " %\n";
    for (const auto& p : f.pairs)
        o << "  tr" << p.truth.trace << " AP" << p.truth.ap << ": " << p.aoa_deg.size()
          << " bearings, median " << median(p.aoa_deg) << " (truth " << p.truth.expected_deg
          << ")\n";
    return o.str();
}

#define MUTRACK_REQUIRE_D1(truthVar, dirVar)                                             \
    const std::string dirVar =                                                           \
        test::sharedDir().empty() ? std::string() : test::sharedDir() + "/data/mutrack"; \
    if (dirVar.empty() || !std::filesystem::exists(dirVar + "/truth_D1.csv"))            \
        GTEST_SKIP() << "muTrack D1 captures not found (../shared/data/mutrack absent)"; \
    const auto truthVar = readTruth(dirVar + "/truth_D1.csv")

}  // namespace

// The endfire lock: D1 tr13 AP5 (truth 4.8 deg) gave -90 deg with sigma 90 in every
// bearing, from weaker angle x delay peaks on the array's endfire rows taken for an earlier
// path. Now the bearing is the path's (other estimators: 15-19 deg).
TEST(MuTrackD1, NoEndfireLockOnTrace13Ap5)
{
    MUTRACK_REQUIRE_D1(truth, dir);
    std::vector<TruthRow> one;
    for (const auto& r : truth)
        if (r.trace == 13 && r.ap == 5) one.push_back(r);
    ASSERT_EQ(one.size(), 1u);
    const Figures f = run(one, dir);
    const auto& p = f.pairs.at(0);
    ASSERT_GE(p.aoa_deg.size(), 100u);
    EXPECT_LT(p.traceError_deg, 15.0) << describe(f);
    // A window whose profile is dominated by such a peak may still report an endfire, but
    // says it can't tell.
    size_t atEndfire = 0;
    for (size_t i = 0; i < p.aoa_deg.size(); ++i)
        if (std::abs(p.aoa_deg[i]) > 80)
        {
            ++atEndfire;
            EXPECT_GE(p.std_deg[i], 45.0) << "bearing " << i << ": " << p.aoa_deg[i] << " deg";
        }
    EXPECT_LT(double(atEndfire), 0.2 * double(p.aoa_deg.size())) << describe(f);
}

// Every (trace, AP) of D1, odd (development) and even (check) traces together.
TEST(MuTrackD1, DefaultBearingsStayWithinTheMeasuredAccuracy)
{
    MUTRACK_REQUIRE_D1(truth, dir);
    ASSERT_EQ(truth.size(), 48u);
    const Figures f = run(truth, dir);
    SCOPED_TRACE(describe(f));
    std::cout << "D1, 48 pairs: " << describe(f).substr(0, describe(f).find('\n')) << "\n";
    for (const auto& p : f.pairs)
        EXPECT_FALSE(p.aoa_deg.empty()) << "tr" << p.truth.trace << " AP" << p.truth.ap;
    EXPECT_LE(f.traceMedian_deg, kMaxTraceMedian_deg);
    EXPECT_LE(f.beyond20_pct, kMaxBeyond20_pct);
    EXPECT_LE(f.packetMedian_deg, kMaxPacketMedian_deg);
    EXPECT_LE(f.packetBeyond30_pct, kMaxPacketBeyond30_pct);
    EXPECT_GE(f.packetWithin3Sigma_pct, kMinWithin3Sigma_pct);
}
