/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * The configuration reference cannot drift from the code: docs/configuration.md, the key
 * registry (mrpt_wifi/obs/ConfigKeys.h) and the keys the code really reads (recorded while it
 * loads each section) must agree, both ways; every key of the .ini files shipped in share/ is
 * known. And the messages for unknown keys: a typo, a key under another name, a key in the
 * wrong section, a former name still accepted. */
#include <gtest/gtest.h>
#include <mrpt/bayes/CParticleFilter.h>
#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/hwdrivers/CGenericSensor.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/maps/TMetricMapInitializer.h>
#include <mrpt/slam/TKLDParams.h>
#include <mrpt/system/filesystem.h>
#include <mrpt/system/string_utils.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>
#include <mrpt_wifi/localization/ParticleRecovery.h>
#include <mrpt_wifi/localization/UnknownMotion.h>
#include <mrpt_wifi/localization/WindowSmoother.h>
#include <mrpt_wifi/obs/ConfigKeys.h>
#include <mrpt_wifi/sensor/CWiFiCSISensor.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <regex>
#include <set>
#include <sstream>

using namespace mrpt_wifi;
namespace fs = std::filesystem;

namespace
{
const std::string kSource = MRPT_WIFI_SOURCE_DIR;

std::string lower(const std::string& s)
{
    return mrpt::system::lowerCase(s);
}

std::string readText(const std::string& path)
{
    std::ifstream f(path);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

/** A config file that records every key read from it (MRPT's read_* all go through
 *  readString()): what the code really reads, section by section. */
class RecordingConfig : public mrpt::config::CConfigFileBase
{
public:
    explicit RecordingConfig(const std::string& text) : inner_(text) {}
    std::map<std::string, std::set<std::string>> reads;  // section -> keys

    void getAllSections(std::vector<std::string>& s) const override { inner_.getAllSections(s); }
    void getAllKeys(const std::string& s, std::vector<std::string>& k) const override
    {
        inner_.getAllKeys(s, k);
    }
    void clear() override { inner_.clear(); }

protected:
    void writeString(const std::string& s, const std::string& k, const std::string& v) override
    {
        inner_.write(s, k, v);
    }
    std::string readString(
        const std::string& s, const std::string& k, const std::string& def,
        bool failIfNotFound) const override
    {
        const_cast<RecordingConfig*>(this)->reads[s].insert(k);
        return inner_.read_string(s, k, def, failIfNotFound);
    }

private:
    mrpt::config::CConfigFileMemory inner_;
};

/** Keys read per section kind of the registry, loading every project section as the programs
 *  do. Sections MRPT reads on the way (the map's generic options) are kept apart. */
std::map<std::string, std::set<std::string>> keysTheCodeReads(
    std::map<std::string, std::set<std::string>>* otherSections = nullptr)
{
    std::map<std::string, std::set<std::string>> byKind;
    const auto collect = [&](const RecordingConfig& c)
    {
        for (const auto& [section, keys] : c.reads)
        {
            bool matched = false;
            for (const auto& kind : config::projectSections())
                if (config::sectionMatches(kind.id, section))
                {
                    byKind[kind.id].insert(keys.begin(), keys.end());
                    matched = true;
                }
            if (!matched && otherSections)
                (*otherSections)[section].insert(keys.begin(), keys.end());
        }
    };
    // Sensors: section names are the user's, the driver's class says the kind.
    for (const auto& [driver, text] : std::vector<std::pair<std::string, std::string>>{
             {"CWiFiCSISensor", "[CWiFiCSISensor]\nprocess_rate = 100\n"},
             {"CWiFiOdometryUdpSensor", "[CWiFiOdometryUdpSensor]\nudp_port = 5501\n"}})
    {
        RecordingConfig c(text);
        auto sensor = mrpt::hwdrivers::CGenericSensor::createSensorPtr(driver);
        EXPECT_TRUE(sensor) << driver;
        if (sensor) sensor->loadConfig(c, driver);
        collect(c);
    }
    {
        // The map: its area keys are read when all four are given.
        RecordingConfig c(
            "[MetricMap]\nwifiBearingMap_count = 1\n"
            "[MetricMap_wifiBearingMap_00_creationOpts]\nmin_x = 0\nmax_x = 1\nmin_y = 0\n"
            "max_y = 1\n");
        mrpt::maps::TSetOfMetricMapInitializers inits;
        inits.loadFromConfigFile(c, "MetricMap");
        collect(c);
    }
    {
        RecordingConfig c("");
        localization::LiveLocalizerOptions().loadFromConfigFile(c, "wifi-localize");
        localization::LiveDeviceMapper(c, "wifi-localize");
        localization::UnknownMotion().loadFromConfigFile(c, "UnknownMotion");
        localization::OdometryMotion().loadFromConfigFile(c, "OdometryMotion");
        localization::ParticleRecoveryOptions().loadFromConfigFile(c, "ParticleRecovery");
        localization::WindowSmootherOptions().loadFromConfigFile(c, "WindowSmoother");
        collect(c);
    }
    return byKind;
}

/** The sources that may read a kind's ReadBy::Program keys: the program's own and the library
 *  it is built on. Empty: the program is MRPT's (rawlog-grabber: `driver`,
 *  `rawlog-grabber-ignore` of the sensors). */
std::vector<std::string> programSourcesOf(const std::string& kind)
{
    std::vector<std::string> files;
    if (kind != "wifi-localize") return files;
    files.push_back(kSource + "/localization_apps/apps/wifi-localize.cpp");
    for (const auto& e : fs::directory_iterator(kSource + "/localization_apps/src"))
        if (e.path().extension() == ".cpp") files.push_back(e.path());
    return files;
}

/** docs/configuration.md's tables: `<!-- keys: ID -->` (a registry kind) or
 *  `<!-- keys: mrpt:SECTION -->` (MRPT's own section), then a table whose first column is the
 *  key in backticks; `<!-- former-keys: ID -->` then a table of former names (first column). */
struct Reference
{
    std::map<std::string, std::vector<std::string>> keys;        // id -> keys, in order
    std::map<std::string, std::vector<std::string>> formerKeys;  // id -> former names
};

Reference parseReference(const std::string& markdown)
{
    Reference ref;
    std::istringstream in(markdown);
    std::string line;
    std::vector<std::string>* table = nullptr;
    bool inTable = false;
    const std::regex marker(R"(<!--\s*(keys|former-keys):\s*(\S+)\s*-->)");
    const std::regex row(R"(^\|\s*`([^`]+)`)");
    while (std::getline(in, line))
    {
        std::smatch m;
        if (std::regex_search(line, m, marker))
        {
            table = m[1] == "keys" ? &ref.keys[m[2]] : &ref.formerKeys[m[2]];
            inTable = false;
            continue;
        }
        if (!table) continue;
        if (line.rfind("|", 0) == 0)
        {
            inTable = true;
            if (std::regex_search(line, m, row)) table->push_back(m[1]);
        }
        else if (inTable)
            table = nullptr;  // the table ended
    }
    return ref;
}

std::string joined(const std::vector<std::string>& v)
{
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
}

/** Where the document and the registry disagree, one line each (empty: they agree). */
std::vector<std::string> referenceProblems(const std::string& markdown)
{
    std::vector<std::string> problems;
    const auto ref = parseReference(markdown);
    for (const auto& kind : config::projectSections())
    {
        const auto it = ref.keys.find(kind.id);
        if (it == ref.keys.end())
        {
            problems.push_back("no table <!-- keys: " + kind.id + " --> in the document");
            continue;
        }
        std::set<std::string> documented;
        for (const auto& k : it->second)
            if (!documented.insert(k).second)
                problems.push_back(kind.id + ": '" + k + "' documented twice");
        for (const auto& k : kind.keys)
            if (!documented.count(k.name))
                problems.push_back(kind.id + ": key '" + k.name + "' is not documented");
        for (const auto& k : documented)
            if (!kind.has(k)) problems.push_back(kind.id + ": documented key '" + k + "' unknown");
        std::set<std::string> formerDocumented;
        if (const auto f = ref.formerKeys.find(kind.id); f != ref.formerKeys.end())
            formerDocumented.insert(f->second.begin(), f->second.end());
        std::set<std::string> former;
        for (const auto& f : kind.formerKeys) former.insert(f.oldName);
        if (former != formerDocumented)
            problems.push_back(
                kind.id + ": former names documented [" +
                joined({formerDocumented.begin(), formerDocumented.end()}) + "], in the code [" +
                joined({former.begin(), former.end()}) + "]");
    }
    for (const auto& [id, keys] : ref.keys)
        if (id.rfind("mrpt", 0) != 0 &&  // mrpt:SECTION, mrpt-driver:CLASS: MRPT's own
            std::none_of(
                config::projectSections().begin(), config::projectSections().end(),
                [&](const auto& k) { return k.id == id; }))
            problems.push_back("table <!-- keys: " + id + " -->: no such section in the code");
    return problems;
}

std::string docsPath()
{
    return kSource + "/docs/configuration.md";
}

/** All .ini files under share/. */
std::vector<std::string> shippedIniFiles()
{
    std::vector<std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(kSource + "/share"))
        if (e.is_regular_file() && e.path().extension() == ".ini") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}

std::string errorOf(const std::string& ini, const std::string& section, const std::string& kind)
{
    mrpt::config::CConfigFileMemory c(ini);
    try
    {
        config::checkSectionKeys(c, section, config::sectionKeys(kind));
    }
    catch (const std::invalid_argument& e)
    {
        return e.what();
    }
    return "";
}

std::string sensorError(const std::string& ini)
{
    mrpt::config::CConfigFileMemory c(ini);
    try
    {
        CWiFiCSISensor().loadConfig(c, "CSI");
    }
    catch (const std::exception& e)
    {
        return e.what();
    }
    return "";
}
}  // namespace

// ---------------------------------------------------------------- the reference

TEST(ConfigReference, RegistryHasTheKeysTheCodeReads)
{
    std::map<std::string, std::set<std::string>> others;
    const auto reads = keysTheCodeReads(&others);
    for (const auto& kind : config::projectSections())
    {
        SCOPED_TRACE(kind.id);
        const auto r = reads.count(kind.id) ? reads.at(kind.id) : std::set<std::string>();
        std::set<std::string> readLower;
        for (const auto& k : r) readLower.insert(lower(k));
        for (const auto& k : r)
        {
            const bool former = std::any_of(
                kind.formerKeys.begin(), kind.formerKeys.end(),
                [&](const auto& f) { return lower(f.oldName) == lower(k); });
            EXPECT_TRUE(kind.has(k) || former) << "read by the code, not in the registry: " << k;
        }
        for (const auto& k : kind.keys)
        {
            if (k.readBy == config::ReadBy::Program)
            {
                const auto sources = programSourcesOf(kind.id);
                if (sources.empty()) continue;
                EXPECT_TRUE(std::any_of(
                    sources.begin(), sources.end(),
                    [&](const std::string& f)
                    { return readText(f).find("\"" + k.name + "\"") != std::string::npos; }))
                    << k.name << " is not read by " << sources.front() << " nor its library";
                continue;
            }
            EXPECT_TRUE(readLower.count(lower(k.name)))
                << "in the registry, not read by the code: " << k.name;
        }
    }
}

TEST(ConfigReference, DocumentMatchesTheRegistry)
{
    ASSERT_TRUE(mrpt::system::fileExists(docsPath())) << docsPath();
    const auto problems = referenceProblems(readText(docsPath()));
    EXPECT_TRUE(problems.empty()) << joined(problems);
}

TEST(ConfigReference, ComparisonFailsWhenARowIsMissingOrExtra)
{
    const std::string doc = readText(docsPath());
    ASSERT_TRUE(referenceProblems(doc).empty());
    // A key of the code left out of the document.
    const std::regex rowOf(R"(\n\|\s*`max_speed_mps`[^\n]*)");
    const std::string withoutRow =
        std::regex_replace(doc, rowOf, "", std::regex_constants::format_first_only);
    ASSERT_NE(withoutRow, doc);
    const auto missing = joined(referenceProblems(withoutRow));
    EXPECT_NE(
        missing.find("UnknownMotion: key 'max_speed_mps' is not documented"), std::string::npos)
        << missing;
    // A documented key the code does not know.
    const std::string extra = std::regex_replace(
        doc, std::regex(R"(\n\|\s*`max_speed_mps`)"), "\n| `max_sped_mps`",
        std::regex_constants::format_first_only);
    ASSERT_NE(extra, doc);
    const auto unknown = joined(referenceProblems(extra));
    EXPECT_NE(unknown.find("documented key 'max_sped_mps' unknown"), std::string::npos) << unknown;
}

TEST(ConfigReference, DocumentedMrptKeysAreReadByMrpt)
{
    const auto ref = parseReference(readText(docsPath()));
    std::map<std::string, std::set<std::string>> mrptReads;
    {
        // With the keys MRPT requires.
        RecordingConfig c(
            "[PF_options]\nadaptiveSampleSize = 0\nBETA = 0.5\nsampleSize = 1\n"
            "PF_algorithm = pfStandardProposal\nresamplingMethod = prSystematic\n");
        mrpt::bayes::CParticleFilter::TParticleFilterOptions().loadFromConfigFile(c, "PF_options");
        mrpt::slam::TKLDParams().loadFromConfigFile(c, "KLD_options");
        localization::odometryMotionModel(c);  // [DummyOdometryParams], as pf-localization
        mrpt::maps::TSetOfMetricMapInitializers().loadFromConfigFile(c, "MetricMap");
        for (const auto& [s, k] : c.reads)
            for (const auto& key : k) mrptReads[lower(s)].insert(lower(key));
    }
    for (const char* s : {"PF_options", "KLD_options", "DummyOdometryParams", "MetricMap"})
    {
        const auto it = ref.keys.find(std::string("mrpt:") + s);
        ASSERT_NE(it, ref.keys.end()) << "no table <!-- keys: mrpt:" << s << " -->";
        for (const auto& k : it->second)
            EXPECT_TRUE(mrptReads[lower(s)].count(lower(k))) << "[" << s << "] " << k;
    }
}

TEST(ConfigReference, ShippedIniFilesUseKnownKeysOnly)
{
    const auto ref = parseReference(readText(docsPath()));
    const auto files = shippedIniFiles();
    ASSERT_FALSE(files.empty());
    for (const auto& file : files)
    {
        SCOPED_TRACE(file);
        mrpt::config::CConfigFile ini(file);
        std::vector<std::string> sections;
        ini.getAllSections(sections);
        for (const auto& section : sections)
        {
            std::vector<std::string> keys;
            ini.getAllKeys(section, keys);
            if (keys.empty()) continue;
            std::string kind;
            const std::string driver = ini.read_string(section, "driver", "");
            for (const auto& k : config::projectSections())
                if ((!driver.empty() && k.id == driver) ||
                    (driver.empty() && config::sectionMatches(k.id, section)))
                    kind = k.id;
            if (!kind.empty())
            {
                std::vector<std::string> notes;
                EXPECT_NO_THROW(
                    notes = config::checkSectionKeys(ini, section, config::sectionKeys(kind)))
                    << "[" << section << "]";
                EXPECT_TRUE(notes.empty())
                    << "[" << section << "] uses a former name: " << joined(notes);
                continue;
            }
            if (!driver.empty())
            {
                // A sensor of MRPT's own (its keys are MRPT's): rawlog-grabber checks none.
                EXPECT_NE(ref.keys.count("mrpt-driver:" + driver), 0u)
                    << "[" << section << "] driver " << driver << " not listed in the document";
                continue;
            }
            const auto it = ref.keys.find("mrpt:" + section);
            ASSERT_NE(it, ref.keys.end()) << "section [" << section << "] is not documented";
            std::set<std::string> documented;
            for (const auto& k : it->second) documented.insert(lower(k));
            for (const auto& k : keys)
                EXPECT_TRUE(documented.count(lower(k)))
                    << "[" << section << "] " << k << " not documented";
        }
    }
}

// ---------------------------------------------------------------- the messages

TEST(ConfigKeys, TypoSuggestsTheKey)
{
    const auto e = errorOf("[UnknownMotion]\nmax_sped_mps = 1\n", "UnknownMotion", "UnknownMotion");
    EXPECT_NE(e.find("section 'UnknownMotion': unknown key 'max_sped_mps'"), std::string::npos)
        << e;
    EXPECT_NE(e.find("did you mean 'max_speed_mps'?"), std::string::npos) << e;
    // Through a real loader: the sensor's.
    const auto s = sensorError("[CSI]\nprocess_rate = 100\nudp_prot = 5500\n");
    EXPECT_NE(
        s.find("section 'CSI': unknown key 'udp_prot' (did you mean 'udp_port'?)"),
        std::string::npos)
        << s;
}

TEST(ConfigKeys, PartOfAKeySuggestsTheWholeKey)
{
    // share/calibration/README.md used to say `calibration = calib/`.
    const auto e = sensorError("[CSI]\nprocess_rate = 100\ncalibration = calib/\n");
    EXPECT_NE(
        e.find("unknown key 'calibration' (did you mean 'bearing_calibration'?)"),
        std::string::npos)
        << e;
    // Several that fit, all named.
    const auto meant = config::likelyMeant("port", config::sectionKeys("CWiFiCSISensor").names());
    EXPECT_EQ(meant, (std::vector<std::string>{"udp_port", "login_port"}));
}

TEST(ConfigKeys, KeyOfAnotherSectionSaysWhereItBelongs)
{
    auto e = errorOf("[wifi-localize]\nmax_speed_mps = 0.5\n", "wifi-localize", "wifi-localize");
    EXPECT_NE(
        e.find("unknown key 'max_speed_mps': it belongs in section 'UnknownMotion'"),
        std::string::npos)
        << e;
    // wifi-localize's own bearing chain key in a sensor section.
    e = sensorError("[CSI]\nprocess_rate = 100\nbearing_stride = 2\n");
    EXPECT_NE(
        e.find("unknown key 'bearing_stride': it belongs in section 'wifi-localize'"),
        std::string::npos)
        << e;
    // A key of several sections names them all; a map section is named with the user's number.
    e = errorOf(
        "[MetricMap_wifiBearingMap_03_creationOpts]\nuse_aoa = false\n",
        "MetricMap_wifiBearingMap_03_creationOpts", "MetricMap_wifiBearingMap_NN_creationOpts");
    EXPECT_NE(
        e.find("it belongs in section 'MetricMap_wifiBearingMap_03_likelihoodOpts'"),
        std::string::npos)
        << e;
    // A typo of another section's key.
    e = errorOf("[ParticleRecovery]\nmax_sped_mps = 1\n", "ParticleRecovery", "ParticleRecovery");
    EXPECT_NE(e.find("did you mean 'max_speed_mps' in section 'UnknownMotion'?"), std::string::npos)
        << e;
}

TEST(ConfigKeys, KeyUnderItsFormerNameIsReadWithANote)
{
    const std::string ini = "[wifi-localize]\nbearing_tx_array = ap.yaml\n";
    mrpt::config::CConfigFileMemory c(ini);
    const auto& kind = config::sectionKeys("wifi-localize");
    std::vector<std::string> notes;
    ASSERT_NO_THROW(notes = config::checkSectionKeys(c, "wifi-localize", kind));
    ASSERT_EQ(notes.size(), 1u);
    EXPECT_NE(
        notes[0].find("'bearing_tx_array' is now called 'bearing_tx_arrays'"), std::string::npos)
        << notes[0];
    EXPECT_EQ(config::readString(c, "wifi-localize", kind, "bearing_tx_arrays", ""), "ap.yaml");
    // The loader of the section accepts it, printing the note.
    std::ostringstream out;
    config::requireKnownKeys(c, "wifi-localize", kind, out);
    EXPECT_NE(
        out.str().find("note: section 'wifi-localize': 'bearing_tx_array' is now called"),
        std::string::npos);
    EXPECT_NO_THROW(localization::LiveLocalizerOptions().loadFromConfigFile(c, "wifi-localize"));
    // Both names at once: which one is meant is not guessed.
    const auto e = errorOf(ini + "bearing_tx_arrays = b.yaml\n", "wifi-localize", "wifi-localize");
    EXPECT_NE(e.find("keep only 'bearing_tx_arrays'"), std::string::npos) << e;
}

TEST(ConfigKeys, FormerNameMovedToAnotherSectionSaysWhere)
{
    mrpt::config::CConfigFileMemory c("[wifi-localize]\nunknown_motion_speed_mps = 0.5\n");
    try
    {
        localization::LiveLocalizerOptions().loadFromConfigFile(c, "wifi-localize");
        FAIL() << "accepted";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(
            std::string(e.what()).find("it is now 'max_speed_mps' in section 'UnknownMotion'"),
            std::string::npos)
            << e.what();
    }
}

TEST(ConfigKeys, KeysAreMatchedWithoutCaseAsMrptReadsThem)
{
    EXPECT_EQ(
        errorOf("[UnknownMotion]\nMax_Speed_MPS = 1\n", "UnknownMotion", "UnknownMotion"), "");
    EXPECT_EQ(sensorError("[CSI]\nprocess_rate = 100\nsensorlabel = X\n"), "");
}

TEST(ConfigKeys, UnknownKeysOfEveryProjectSectionAreCaught)
{
    const auto expectNamed = [](const std::function<void()>& load, const std::string& key)
    {
        try
        {
            load();
            ADD_FAILURE() << key << " accepted";
        }
        catch (const std::exception& e)
        {
            EXPECT_NE(std::string(e.what()).find("unknown key '" + key + "'"), std::string::npos)
                << e.what();
        }
    };
    mrpt::config::CConfigFileMemory c(
        "[wifi-localize]\nbogus_a = 1\n[UnknownMotion]\nbogus_b = 1\n[OdometryMotion]\nbogus_c = "
        "1\n"
        "[ParticleRecovery]\nbogus_d = 1\n[WindowSmoother]\nbogus_e = 1\n"
        "[M_likelihoodOpts]\nbogus_f = 1\n[ODO]\nudp_port = 1\nbogus_g = 1\n");
    expectNamed(
        [&] { localization::LiveLocalizerOptions().loadFromConfigFile(c, "wifi-localize"); },
        "bogus_a");
    expectNamed(
        [&] { localization::UnknownMotion().loadFromConfigFile(c, "UnknownMotion"); }, "bogus_b");
    expectNamed(
        [&] { localization::OdometryMotion().loadFromConfigFile(c, "OdometryMotion"); }, "bogus_c");
    expectNamed(
        [&] { localization::ParticleRecoveryOptions().loadFromConfigFile(c, "ParticleRecovery"); },
        "bogus_d");
    expectNamed(
        [&] { localization::WindowSmootherOptions().loadFromConfigFile(c, "WindowSmoother"); },
        "bogus_e");
    expectNamed(
        [&] { CWiFiBearingMap::TLikelihoodOptions().loadFromConfigFile(c, "M_likelihoodOpts"); },
        "bogus_f");
    expectNamed(
        [&]
        {
            auto s = mrpt::hwdrivers::CGenericSensor::createSensorPtr("CWiFiOdometryUdpSensor");
            s->loadConfig(c, "ODO");
        },
        "bogus_g");
    // The map's creation options: reported when the map is made (MRPT's loader keeps going).
    mrpt::config::CConfigFileMemory m(
        "[MetricMap]\nwifiBearingMap_count = 1\n"
        "[MetricMap_wifiBearingMap_00_creationOpts]\ntransmiters_file = aps.yaml\n");
    mrpt::maps::TSetOfMetricMapInitializers inits;
    inits.loadFromConfigFile(m, "MetricMap");
    try
    {
        mrpt::maps::CMultiMetricMap maps;
        maps.setListOfMaps(inits);
        ADD_FAILURE() << "map made";
    }
    catch (const std::exception& e)
    {
        EXPECT_NE(
            std::string(e.what()).find(
                "unknown key 'transmiters_file' (did you mean 'transmitters_file'?)"),
            std::string::npos)
            << e.what();
    }
}

TEST(ConfigKeys, MisspeltSectionIsNamedWithTheSectionMeant)
{
    mrpt::config::CConfigFileMemory c(
        "[UnknowMotion]\nmax_speed_mps = 1\n[MetricMap_wifiBearingMap_00_likelihoodOpt]\n"
        "use_aoa = false\n[Notes]\nx = 1\n[WIFI_CSI]\ndriver = CWiFiCSISensor\n"
        "[UnknownMotion]\nmax_speed_mps = 1\n[MetricMap_occupancyGrid_00_creationOpts]\n"
        "resolution = 0.1\n[pf_options]\nBETA = 0.5\n");
    const auto w = config::unreadSections(c, config::pfLocalizationMrptSections());
    ASSERT_EQ(w.size(), 3u) << joined(w);
    const auto all = joined(w);  // in the order MRPT lists the sections
    EXPECT_NE(
        all.find("section 'UnknowMotion' is not read by this program (did you mean "
                 "'UnknownMotion'?)"),
        std::string::npos)
        << all;
    EXPECT_NE(
        all.find("section 'MetricMap_wifiBearingMap_00_likelihoodOpt' is not read by this "
                 "program (did you mean 'MetricMap_wifiBearingMap_00_likelihoodOpts'?)"),
        std::string::npos)
        << all;
    EXPECT_NE(
        all.find("section 'Notes' is not read by this program (its keys have no effect)"),
        std::string::npos)
        << all;
    // The shipped files have none.
    for (const auto& file : shippedIniFiles())
        if (file.find("/localization/") != std::string::npos)
        {
            mrpt::config::CConfigFile ini(file);
            EXPECT_TRUE(config::unreadSections(ini, config::pfLocalizationMrptSections()).empty())
                << file;
        }
}
