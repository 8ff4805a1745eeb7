/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CConfigFileBase.h>

#include <iosfwd>
#include <string>
#include <vector>

/** The keys of every .ini section the project's plugins and programs read, in one registry:
 *  the code rejects a key its section does not know (suggesting the key meant, also when it
 *  lives under another name or in another section), and docs/configuration.md documents the
 *  same list (tests/apps/test_config_reference.cpp compares the three: registry, the keys the
 *  code really reads, the document). */
namespace mrpt_wifi::config
{
/** Who reads a key. */
enum class ReadBy
{
    Section,  //!< the project's code that loads (and checks) the section
    Mrpt,     //!< MRPT's code for the same section (CGenericSensor::loadConfig, a map's
              //!< generic options)
    Program   //!< the program around it: rawlog-grabber's or wifi-localize's main
};

struct Key
{
    std::string name;
    ReadBy readBy = ReadBy::Section;
};

/** A key's former name. With `newSection` empty the key only changed its name in the same
 *  section: the old name is still read, with a note. Else it moved to another section and the
 *  old name is an error saying where it lives now. */
struct FormerKey
{
    std::string oldName;
    std::string newName;
    std::string newSection;  //!< a SectionKeys::id, or empty
};

/** The keys of one kind of section. */
struct SectionKeys
{
    /** "wifi-localize", "UnknownMotion", ... (the section's own name); a sensor driver's class
     *  name for its sections ("CWiFiCSISensor": [WIFI_CSI] in the shipped files); for the
     *  bearing map "MetricMap_wifiBearingMap_NN_creationOpts" (NN = 00, 01, ...). */
    std::string id;
    /** How to name the section in a message: "section 'UnknownMotion'", "a CWiFiCSISensor
     *  section". No brackets: MRPT's text of an exception thrown in a sensor's loadConfig()
     *  ends at the first '['. */
    std::string title;
    std::vector<Key> keys;
    std::vector<FormerKey> formerKeys;

    bool has(const std::string& key) const;  //!< case-insensitive, as MRPT reads keys
    std::vector<std::string> names() const;
};

/** Every section kind of the project (not MRPT's own sections such as PF_options). */
const std::vector<SectionKeys>& projectSections();

/** The keys of section kind `id`; throws std::logic_error for an id not in the registry. */
const SectionKeys& sectionKeys(const std::string& id);

/** Whether `section` (a real name such as "MetricMap_wifiBearingMap_01_likelihoodOpts") is of
 *  kind `id`. */
bool sectionMatches(const std::string& id, const std::string& section);

/** Levenshtein distance (insertions, deletions, substitutions). */
size_t editDistance(const std::string& a, const std::string& b);

/** The names of `known` that `name` most likely means, best first (at most 3; empty when none is
 *  close): a typo (edit distance up to a third of the name, at most 3, case ignored), else names
 *  that contain `name` (`calibration` → `bearing_calibration`), shortest first (much longer
 *  ones only when nothing shorter contains it). */
std::vector<std::string> likelyMeant(
    const std::string& name, const std::vector<std::string>& known);

/** Checks every key of [section] against the kind `keys`. Returns notes for former names still
 *  accepted (the reader of the key reads them through readString()). Throws
 *  std::invalid_argument "section 'S': unknown key 'k' ..." for a key the section does not know,
 *  saying which key was likely meant: a typo of one of its keys, a key whose name contains it,
 *  a key now under another name, or the section(s) it belongs to. */
std::vector<std::string> checkSectionKeys(
    const mrpt::config::CConfigFileBase& ini, const std::string& section, const SectionKeys& keys);

/** checkSectionKeys(), the notes written to `notes` as "note: ..." lines. */
void requireKnownKeys(
    const mrpt::config::CConfigFileBase& ini, const std::string& section, const SectionKeys& keys,
    std::ostream& notes);
/** The same, notes to std::cerr. */
void requireKnownKeys(
    const mrpt::config::CConfigFileBase& ini, const std::string& section, const SectionKeys& keys);

/** The sections of MRPT's pf-localization that the particle-filter programs (wifi-pf-localization,
 *  wifi-localize) read through MRPT: LocalizationExperiment, PF_options, KLD_options,
 *  DummyOdometryParams, MetricMap; "MetricMap_*" stands for the sections of MRPT's other maps. */
const std::vector<std::string>& pfLocalizationMrptSections();

/** Warnings for the sections of `ini` that nothing reads, each with the section likely meant: a
 *  misspelt section name (`[UnknowMotion]`) would leave all its keys unread without a word. A
 *  section is read when it has a `driver` (a sensor), is one of projectSections() or one of
 *  `mrptSections` (case ignored; a trailing '*' matches a prefix, except for the bearing map's
 *  own sections, which must be the registry's). */
std::vector<std::string> unreadSections(
    const mrpt::config::CConfigFileBase& ini, const std::vector<std::string>& mrptSections);

/** The value of `key`, or of a former name of it still accepted, or `defaultValue`. */
std::string readString(
    const mrpt::config::CConfigFileBase& ini, const std::string& section, const SectionKeys& keys,
    const std::string& key, const std::string& defaultValue);

}  // namespace mrpt_wifi::config
