/* mrpt_wifi — WiFi channel state information for MRPT.  */
// No input aborts a program (issue 52): the localization programs' text readers (bearings CSV,
// TUM and CSV trajectories, the AP map YAML) and the project's .ini values either give a result
// or throw a std::exception whose message names the file or the key, for random damage to valid
// inputs from a fixed seed; the no-odometry motion stays usable by MRPT's particle filter
// however wide it gets; the map's area follows the init_PDF box, with a warning when both are
// given and disagree. (tests/fuzz/fuzz_text_inputs.cpp fuzzes the same readers.)
#include <gtest/gtest.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/vector_loadsave.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/slam/CMonteCarloLocalization2D.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/localization/IniValues.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>
#include <mrpt_wifi/localization/ParticleRecovery.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/localization/WindowSmoother.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

// MRPT 2.5.8's YAML reader leaks libfyaml's parser and input on some syntax errors ("wrongly
// indented block sequence in flow mode", malformed UTF-8): not this project's memory. Every
// other leak still fails the run (LeakSanitizer reads this hook; other builds ignore it).
extern "C" const char* __lsan_default_suppressions()
{
    return "leak:libfyaml.so\n";
}

namespace
{
const char* kApsYaml =
    "transmitters:\n"
    "  - {name: ap-a, mac: '02:00:00:00:0a:01', position: [0.5, 0.5], yaw_deg: 45}\n"
    "  - {name: ap-b, mac: '02:00:00:00:0a:02', position: [9.5, 4.5], yaw_deg: -135,\n"
    "     array_elements: [[0, -0.039], [0, -0.013], [0, 0.013], [0, 0.039]]}\n";

const char* kBearingsCsv =
    "# comment\n"
    "timestamp,transmitter,aoa_deg,aoa_std_deg,aoa_mirror_deg,aod_deg,aod_std_deg,"
    "aod_mirror_deg,has_aoa,has_aod,aoa_alt_deg,aoa_alt_weight,aoa_direction_std_deg\n"
    "1700000000.10,02:00:00:00:0a:01,23.5,4.0,156.5,-12.0,5.0,,1,1,-40,0.3,3\n"
    "1700000000.10,ap-b,,,,-12.0,5.0,192,0,1,,,\n"
    "1700000000.20,ap-a,10,3,,,,,1,0,,,\n";

const char* kTum =
    "# t x y z qx qy qz qw\n"
    "1700000000.0 1 2 0 0 0 0 1\n"
    "1700000000.1 1.05 2 0 0 0 0.0499792 0.9987503\n"
    "1700000000.2 1.10 2.01 0 0 0 0.0998334 0.9950042\n";

const char* kWsrCsv =
    "1700000000,0,1,2,0,0,0,0,1\n1700000000,100000000,1.05,2,0,0,0,0,1\n"
    "1700000000.5,0,1.1,2.0,0.3\n";

/** Random damage to a text: characters replaced, inserted, deleted, lines duplicated or cut,
 *  tokens that trouble number parsers. */
std::string damaged(const std::string& text, std::mt19937& rng)
{
    static const std::vector<std::string> tokens = {
        "nan",
        "inf",
        "-inf",
        "1e400",
        "-1e400",
        "1e-400",
        "99999999999999999999",
        "0x1p3",
        "",
        ",",
        ",,",
        "\n",
        "#",
        ":",
        "[",
        "]",
        "{",
        "}",
        "'",
        "\"",
        "-",
        "  ",
        "\t",
        "\r",
        "\xff\xfe",
        "02:00:00:00:0a:01",
        "ap-a",
        "1700000000",
        "-0",
        "+",
        ".",
        "e5",
        "true"};
    std::string s = text;
    std::uniform_int_distribution<int> nOps(1, 6), op(0, 5);
    for (int i = nOps(rng); i > 0; --i)
    {
        const size_t pos = s.empty() ? 0 : std::uniform_int_distribution<size_t>(0, s.size())(rng);
        const auto& tok = tokens[std::uniform_int_distribution<size_t>(0, tokens.size() - 1)(rng)];
        switch (op(rng))
        {
            case 0:  // replace a character by a random byte
                if (pos < s.size()) s[pos] = char(std::uniform_int_distribution<int>(0, 255)(rng));
                break;
            case 1:  // insert a token
                s.insert(pos, tok);
                break;
            case 2:  // delete a run
                if (pos < s.size()) s.erase(pos, std::uniform_int_distribution<size_t>(1, 12)(rng));
                break;
            case 3:  // replace the next number-ish run by a token
            {
                const size_t b = s.find_first_of("0123456789", pos);
                if (b == std::string::npos) break;
                const size_t e = s.find_first_not_of("0123456789.e-", b);
                s.replace(b, (e == std::string::npos ? s.size() : e) - b, tok);
                break;
            }
            case 4:  // duplicate a line
            {
                const size_t b = s.rfind('\n', pos);
                const size_t from = b == std::string::npos ? 0 : b + 1;
                const size_t e = s.find('\n', from);
                s.insert(from, s.substr(from, (e == std::string::npos ? s.size() : e + 1) - from));
                break;
            }
            default:  // cut the text
                s.resize(pos);
                break;
        }
    }
    return s;
}

/** `read` on `samples` damaged texts of `valid`: each gives a result or throws a std::exception
 *  whose message contains `mustName` (the file or the map's display name). Returns how many
 *  parsed (so a test can tell it did not only exercise the error path). */
size_t expectParsesOrNamedError(
    const std::string& valid, const std::string& mustName, unsigned seed,
    const std::function<void(const std::string&)>& read, size_t samples = 400)
{
    std::mt19937 rng(seed);
    size_t parsed = 0;
    for (size_t i = 0; i < samples; ++i)
    {
        const std::string text = i == 0 ? valid : damaged(valid, rng);
        try
        {
            read(text);
            ++parsed;
        }
        catch (const std::exception& e)
        {
            EXPECT_NE(std::string(e.what()).find(mustName), std::string::npos)
                << "error without the input's name: '" << e.what() << "' for:\n"
                << text;
        }
        catch (...)
        {
            ADD_FAILURE() << "an exception that is not a std::exception for:\n" << text;
        }
    }
    return parsed;
}

std::string writeText(const std::string& path, const std::string& text)
{
    std::ofstream(path, std::ios::binary) << text;
    return path;
}

bool finitePose(const mrpt::math::TPose2D& p)
{
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.phi);
}
}  // namespace

TEST(InputProperties, BearingCsvParsesOrNamesTheFile)
{
    const auto names = TransmitterMap::fromYamlText(kApsYaml);
    const std::string path = mrpt_wifi::test::tempPath("_bearings.csv");
    const size_t parsed = expectParsesOrNamedError(
        kBearingsCsv, path, 11,
        [&](const std::string& text)
        {
            BearingCsvOptions o;
            o.names = &names;
            InputWarnings w;
            for (const auto& b : readBearingCsv(writeText(path, text), o, &w))
            {
                ASSERT_TRUE(std::isfinite(b.t)) << text;
                if (b.hasAoa)
                {
                    ASSERT_TRUE(std::isfinite(b.aoa) && std::isfinite(b.aoaStd)) << text;
                }
                if (b.hasAod)
                {
                    ASSERT_TRUE(std::isfinite(b.aod) && std::isfinite(b.aodStd)) << text;
                }
            }
        });
    EXPECT_GT(parsed, 10u);
}

TEST(InputProperties, TumAndCsvTrajectoriesParseOrNameTheFile)
{
    for (const bool tum : {true, false})
    {
        const std::string path = mrpt_wifi::test::tempPath(tum ? "_traj.txt" : "_traj.csv");
        const size_t parsed = expectParsesOrNamedError(
            tum ? kTum : kWsrCsv, path, tum ? 12 : 13,
            [&](const std::string& text)
            {
                writeText(path, text);
                const auto t =
                    tum ? Trajectory2D::fromTumFile(path) : Trajectory2D::fromWsrCsv(path);
                for (size_t i = 0; i < t.size(); ++i)
                    ASSERT_TRUE(std::isfinite(t.t[i]) && finitePose(t.poses[i])) << text;
            });
        EXPECT_GT(parsed, 10u) << (tum ? "TUM" : "CSV");
    }
}

TEST(InputProperties, ApMapYamlParsesOrNamesTheFile)
{
    const size_t parsed = expectParsesOrNamedError(
        kApsYaml, "aps-under-test.yaml", 14,
        [&](const std::string& text)
        {
            const auto m =
                TransmitterMap::fromYamlText(text, "aps-under-test.yaml", "/nonexistent");
            for (const auto& t : m.transmitters()) ASSERT_TRUE(finitePose(t.pose)) << text;
            (void)m.asYamlText();
        });
    EXPECT_GT(parsed, 10u);
}

// Every number and switch of the project's localization sections, set to text MRPT's readers
// would silently turn into another value (or out of range): the section's loader says which
// key it cannot take.
TEST(InputProperties, IniValuesOutOfRangeEmptyOrNotNumbersAreNamedErrors)
{
    struct Section
    {
        std::string name;
        std::vector<std::string> numbers, switches;
        std::function<void(const mrpt::config::CConfigFileBase&)> load;
    };
    const std::vector<Section> sections = {
        {"UnknownMotion",
         {"max_speed_mps", "max_turn_rate_dps", "correlation_time_s", "max_step_s", "min_std_xy",
          "min_std_phi_deg", "velocity_window_s", "wide_fraction", "wide_correlation_time_s",
          "bearing_weight"},
         {"constant_velocity", "forward_only"},
         [](const auto& c)
         {
             UnknownMotion m;
             m.loadFromConfigFile(c, "UnknownMotion");
         }},
        {"OdometryMotion",
         {"std_xy_per_sqrt_m", "std_phi_deg_per_sqrt_m", "std_xy_per_sqrt_s",
          "std_phi_deg_per_sqrt_s", "max_step_s", "jump_rate_hz", "jump_std_xy_m",
          "jump_std_phi_deg", "bearing_weight"},
         {},
         [](const auto& c)
         {
             OdometryMotion m;
             m.loadFromConfigFile(c, "OdometryMotion");
         }},
        {"ParticleRecovery",
         {"rate_hz", "window_s", "min_agreement", "max_std_deg"},
         {},
         [](const auto& c)
         {
             ParticleRecoveryOptions o;
             o.loadFromConfigFile(c, "ParticleRecovery");
         }},
        {"WindowSmoother",
         {"window_s", "min_window_s", "solve_period_s", "max_median_whitened_residual",
          "max_filter_spread_m", "max_recent_residual_deg", "track_window_s", "track_node_period_s",
          "track_accel_std", "track_turn_accel_std_deg", "track_lateral_std_m", "track_switch_cost",
          "track_restart_headings"},
         {"enabled", "without_odometry"},
         [](const auto& c)
         {
             WindowSmootherOptions o;
             o.loadFromConfigFile(c, "WindowSmoother");
         }},
        {"wifi-localize",
         {"max_bearings_per_step", "max_queue_s", "bearing_bias_std_deg"},
         {},
         [](const auto& c)
         {
             LiveLocalizerOptions o;
             o.loadFromConfigFile(c, "wifi-localize");
         }},
        {"MetricMap_wifiBearingMap_00_likelihoodOpts",
         {"outlier_prob", "min_std_deg", "max_std_deg", "std_scale", "aoa_alternative_share",
          "bearing_weight"},
         {"use_aoa", "use_aod"},
         [](const auto& c)
         {
             CWiFiBearingMap::TLikelihoodOptions o;
             o.loadFromConfigFile(c, "MetricMap_wifiBearingMap_00_likelihoodOpts");
         }},
        {"LocalizationExperiment",
         {"init_PDF_min_x", "init_PDF_max_x", "init_PDF_min_y", "init_PDF_max_y"},
         {},
         [](const auto& c) { (void)initialPdfArea(c); }},
    };
    // The shipped values load (the loaders accept what the project ships).
    const std::string shipped = mrpt::io::file_get_contents(
        std::string(MRPT_WIFI_SOURCE_DIR) + "/share/localization/pf-localization-wifi.ini");
    {
        mrpt::config::CConfigFileMemory ini;
        ini.setContent(shipped);
        for (const auto& s : sections)
        {
            if (s.name != "wifi-localize")
            {
                EXPECT_NO_THROW(s.load(ini)) << s.name;
            }
        }
    }
    const std::vector<std::string> notNumbers = {"",     "abc",   "1.5x", "nan", "inf",
                                                 "-inf", "1e400", "1,5",  "true"};
    const std::vector<std::string> notSwitches = {"", "on", "maybe", "2x", "true ; yes"};
    for (const auto& s : sections)
    {
        for (const auto& k : s.numbers)
            for (const auto& v : notNumbers)
            {
                mrpt::config::CConfigFileMemory ini;
                ini.setContent(shipped);
                ini.write(s.name, k, v);
                try
                {
                    s.load(ini);
                    ADD_FAILURE() << "[" << s.name << "] " << k << " = '" << v << "' accepted";
                }
                catch (const std::exception& e)
                {
                    EXPECT_NE(std::string(e.what()).find(k), std::string::npos)
                        << "[" << s.name << "] " << k << " = '" << v << "': " << e.what();
                }
            }
        for (const auto& k : s.switches)
            for (const auto& v : notSwitches)
            {
                mrpt::config::CConfigFileMemory ini;
                ini.setContent(shipped);
                ini.write(s.name, k, v);
                try
                {
                    s.load(ini);
                    ADD_FAILURE() << "[" << s.name << "] " << k << " = '" << v << "' accepted";
                }
                catch (const std::exception& e)
                {
                    EXPECT_NE(std::string(e.what()).find(k), std::string::npos) << e.what();
                }
            }
        // Out of range: negative and huge values either load or name the key.
        for (const auto& k : s.numbers)
            for (const char* v : {"-1", "0", "1e300", "-1e300"})
            {
                mrpt::config::CConfigFileMemory ini;
                ini.setContent(shipped);
                ini.write(s.name, k, v);
                try
                {
                    s.load(ini);
                }
                catch (const std::exception& e)
                {
                    EXPECT_FALSE(std::string(e.what()).empty()) << k << " = " << v;
                }
            }
    }
}

TEST(InputProperties, IniNumberAndSwitchSyntax)
{
    for (const char* ok : {"0", "-1.5", "2e3", " 7 ", "5 ; metres", "5 # metres", "5 // m"})
        EXPECT_TRUE(isIniNumber(ok)) << ok;
    for (const char* bad : {"", "abc", "1.5x", "nan", "inf", "1e400", "1,5", "0.5 m"})
        EXPECT_FALSE(isIniNumber(bad)) << bad;
    mrpt::config::CConfigFileMemory c;
    c.setContent("[s]\na = TRUE\nb = no\nc = 1\nd = on\n");
    EXPECT_NO_THROW(requireIniBools(c, "s", {"a", "b", "c", "missing"}));
    EXPECT_THROW(requireIniBools(c, "s", {"d"}), std::invalid_argument);
}

// MRPT's CActionCollection::getBestMovementEstimation() drops a motion whose covariance
// determinant is 1e3 or more, and its filter then throws "Action list does not contain any
// CActionRobotMovement2D ..." (in pf-localization's worker thread: an abort, issue 52).
TEST(NoOdometryPath, ReseedingOverALargeAreaStaysTheFiltersMotion)
{
    UnknownMotion motion;
    const auto walk = motion.makeAction(0.5, mrpt::poses::CPose2D(0.2, 0, 0));
    // 26 x 18 m: the re-seeding disc's radius is the area's diagonal.
    const double radius = std::hypot(26.0, 18.0);
    for (const double share : {0.05, 0.2, 0.39, 0.5})
    {
        const auto a = withReseeding(*walk, share, radius);
        mrpt::obs::CActionCollection acts;
        acts.insert(a);
        ASSERT_TRUE(acts.getBestMovementEstimation()) << "share " << share;
        // The filter takes it: one step of MRPT's particle filter on it.
        mrpt::slam::CMonteCarloLocalization2D pdf(100);
        pdf.resetUniform(0, 26, 0, 18, -M_PI, M_PI, 100);
        pdf.options.metricMap = std::make_shared<mrpt::maps::CMultiMetricMap>();
        mrpt::bayes::CParticleFilter pf;
        mrpt::obs::CSensoryFrame sf;
        EXPECT_NO_THROW(pf.executeOn(pdf, &acts, &sf)) << "share " << share;
    }
    // A narrow motion keeps its odometry form (stored as the reading and the model).
    const auto narrow = withReseeding(*walk, 0.0, radius);
    EXPECT_EQ(narrow.estimationMethod, mrpt::obs::CActionRobotMovement2D::emOdometry);
}

TEST(NoOdometryPath, AnyAcceptedUnknownMotionGivesUsableActions)
{
    std::mt19937 rng(15);
    std::uniform_real_distribution<double> logU(-3, 3);
    for (int i = 0; i < 200; ++i)
    {
        UnknownMotion m;
        m.maxSpeed_mps = std::pow(10.0, logU(rng));
        m.maxTurnRate_dps = std::pow(10.0, logU(rng) + 1);
        m.correlationTime_s = std::pow(10.0, logU(rng));
        m.wideCorrelationTime_s = std::pow(10.0, logU(rng));
        m.maxStep_s = std::pow(10.0, logU(rng));
        m.wideFraction = std::uniform_real_distribution<double>(0, 1)(rng);
        ASSERT_NO_THROW(m.validate());
        for (const double dt : {0.0, 0.01, 0.5, 100.0})
        {
            const auto a = m.makeAction(dt, mrpt::poses::CPose2D(0.1, 0.0, 0.05));
            mrpt::obs::CActionCollection acts;
            acts.insert(*a);
            ASSERT_TRUE(acts.getBestMovementEstimation())
                << m.asString() << " dt " << dt << " wide " << m.wideFraction;
        }
    }
}

// The map's area and the init_PDF box: one source of truth by default.
namespace
{
CWiFiBearingMap::Ptr mapFrom(const std::string& lpSection, const std::string& area)
{
    static const std::string aps = writeText(mrpt_wifi::test::tempPath("_aps.yaml"), kApsYaml);
    mrpt::config::CConfigFileMemory ini;
    ini.setContent(
        "[LocalizationExperiment]\ninit_PDF_mode = 1\n" + lpSection +
        "[MetricMap]\nwifiBearingMap_count = 1\n"
        "[MetricMap_wifiBearingMap_00_creationOpts]\ntransmitters_file = " +
        aps + "\n" + area);
    return wifiMapFromIni(ini, ".");
}
const std::string kBox5x10 =
    "init_PDF_min_x = 0\ninit_PDF_max_x = 5\ninit_PDF_min_y = 0\ninit_PDF_max_y = 10\n";
mrpt::config::CConfigFileMemory iniOf(const std::string& lp)
{
    mrpt::config::CConfigFileMemory ini;
    ini.setContent("[LocalizationExperiment]\ninit_PDF_mode = 1\n" + lp);
    return ini;
}
}  // namespace

TEST(MapArea, TakenFromTheInitBoxWhenNotGiven)
{
    auto map = mapFrom(kBox5x10, "");
    ASSERT_TRUE(map->area());
    EXPECT_TRUE(map->areaFromInitialPdf());
    EXPECT_DOUBLE_EQ(map->area()->max.x, 5);
    EXPECT_DOUBLE_EQ(map->area()->max.y, 10);
    std::string warning = "x";
    EXPECT_TRUE(boundByInitialPdf(*map, iniOf(kBox5x10), &warning));
    EXPECT_EQ(warning, "");
}

TEST(MapArea, NoAreaWithoutAUniformInitBox)
{
    auto map = mapFrom("init_PDF_mode = 0\n", "");
    EXPECT_FALSE(map->area());
    EXPECT_FALSE(map->areaFromInitialPdf());
}

TEST(MapArea, TheSameAreaTwiceIsNoWarning)
{
    auto map = mapFrom(kBox5x10, "min_x = 0\nmax_x = 5\nmin_y = 0\nmax_y = 10\n");
    std::string warning;
    EXPECT_FALSE(boundByInitialPdf(*map, iniOf(kBox5x10), &warning));
    EXPECT_EQ(warning, "");
}

TEST(MapArea, AnInitBoxOutsideTheAreaWidensItWithAWarning)
{
    auto map = mapFrom(kBox5x10, "min_x = 0\nmax_x = 10\nmin_y = 0\nmax_y = 5\n");
    std::string warning;
    EXPECT_FALSE(boundByInitialPdf(*map, iniOf(kBox5x10), &warning));
    EXPECT_NE(warning.find("init_PDF box"), std::string::npos) << warning;
    EXPECT_NE(warning.find("reaches outside the map's area"), std::string::npos) << warning;
    EXPECT_NE(warning.find("widened to x 0..10, y 0..10 m"), std::string::npos) << warning;
    ASSERT_TRUE(map->area());
    EXPECT_DOUBLE_EQ(map->area()->max.x, 10);
    EXPECT_DOUBLE_EQ(map->area()->max.y, 10);
}

TEST(MapArea, AnAreaLargerThanTheInitBoxIsKeptWithAWarning)
{
    auto map = mapFrom(kBox5x10, "min_x = -5\nmax_x = 20\nmin_y = 0\nmax_y = 10\n");
    std::string warning;
    EXPECT_FALSE(boundByInitialPdf(*map, iniOf(kBox5x10), &warning));
    EXPECT_NE(warning.find("is larger than the init_PDF box"), std::string::npos) << warning;
    EXPECT_DOUBLE_EQ(map->area()->min.x, -5);
    EXPECT_DOUBLE_EQ(map->area()->max.x, 20);
}

TEST(MapArea, NotANumberInTheAreaOrTheBoxIsNamed)
{
    try
    {
        mapFrom(kBox5x10, "min_x = 0\nmax_x = ten\nmin_y = 0\nmax_y = 5\n");
        ADD_FAILURE() << "max_x = ten accepted";
    }
    catch (const std::exception& e)
    {
        EXPECT_NE(std::string(e.what()).find("max_x = 'ten'"), std::string::npos) << e.what();
    }
    try
    {
        mapFrom(
            "init_PDF_min_x = 0\ninit_PDF_max_x = 5m\ninit_PDF_min_y = 0\ninit_PDF_max_y = 10\n",
            "");
        ADD_FAILURE() << "init_PDF_max_x = 5m accepted";
    }
    catch (const std::exception& e)
    {
        EXPECT_NE(std::string(e.what()).find("init_PDF_max_x"), std::string::npos) << e.what();
    }
}

TEST(InputProperties, NonFiniteNumbersAreRefusedNamingTheFile)
{
    const auto names = TransmitterMap::fromYamlText(kApsYaml);
    const std::string csv = mrpt_wifi::test::tempPath("_nan.csv");
    const std::string tum = mrpt_wifi::test::tempPath("_nan.txt");
    for (const char* v : {"nan", "inf", "1e999"})
    {
        BearingCsvOptions o;
        o.names = &names;
        writeText(csv, std::string("timestamp,transmitter,aod_deg\n1700000000,ap-a,") + v + "\n");
        if (std::string(v) == "nan")
        {
            // The CSV's way to leave a cell unmeasured (as pandas writes it): counted, not read.
            InputWarnings w;
            EXPECT_TRUE(readBearingCsv(csv, o, &w).empty());
            EXPECT_EQ(w.noAngle, 1u);
        }
        else
            EXPECT_THROW(readBearingCsv(csv, o), std::exception) << v;
        writeText(csv, std::string("1700000000,0,") + v + ",2,0,0,0,0,1\n");
        try
        {
            Trajectory2D::fromWsrCsv(csv);
            ADD_FAILURE() << v << " accepted as a position";
        }
        catch (const std::exception& e)
        {
            EXPECT_NE(std::string(e.what()).find(csv + ":1"), std::string::npos) << e.what();
        }
        writeText(tum, std::string("1700000000 ") + v + " 2 0 0 0 0 1\n");
        EXPECT_THROW(Trajectory2D::fromTumFile(tum), std::exception) << v;
    }
}

TEST(InputProperties, ApMapInAnotherEncodingIsNamed)
{
    // "café" in Latin-1: the byte 0xE9 alone.
    const std::string latin1 = std::string(kApsYaml) + "# caf\xe9\n";
    try
    {
        TransmitterMap::fromYamlText(latin1, "aps-latin1.yaml");
        ADD_FAILURE() << "Latin-1 text accepted";
    }
    catch (const std::exception& e)
    {
        EXPECT_NE(
            std::string(e.what()).find("aps-latin1.yaml:5: not UTF-8 text"), std::string::npos)
            << e.what();
    }
    EXPECT_NO_THROW(TransmitterMap::fromYamlText(std::string(kApsYaml) + "# caf\xc3\xa9\n"));
}
