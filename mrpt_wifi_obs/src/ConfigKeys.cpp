/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/system/string_utils.h>
#include <mrpt_wifi/obs/ConfigKeys.h>

#include <algorithm>
#include <cctype>
#include <iostream>
#include <stdexcept>

namespace mrpt_wifi::config
{
namespace
{
std::string lower(const std::string& s)
{
    return mrpt::system::lowerCase(s);
}

bool sameName(const std::string& a, const std::string& b)
{
    return lower(a) == lower(b);
}

std::vector<std::string> bestThree(std::vector<std::pair<size_t, std::string>> found)
{
    std::stable_sort(
        found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<std::string> best;
    for (const auto& f : found)
        if (best.size() < 3 && std::find(best.begin(), best.end(), f.second) == best.end())
            best.push_back(f.second);
    return best;
}

/** Known names a few letters away: fewer than a third of the name, at most 3. */
std::vector<std::string> typosOf(const std::string& name, const std::vector<std::string>& known)
{
    const std::string n = lower(name);
    const size_t maxTypo = std::min<size_t>(3, std::max<size_t>(1, n.size() / 3));
    std::vector<std::pair<size_t, std::string>> found;
    for (const auto& k : known)
        if (const size_t d = editDistance(n, lower(k)); d <= maxTypo) found.push_back({d, k});
    return bestThree(std::move(found));
}

/** Known names that contain the name (`calibration` in `bearing_calibration`), shortest first;
 *  much longer ones (`bearing_calibration_max_age_days`) only when nothing shorter does. */
std::vector<std::string> partsOf(const std::string& name, const std::vector<std::string>& known)
{
    const std::string n = lower(name);
    std::vector<std::pair<size_t, std::string>> found;
    if (n.size() >= 4)
        for (const auto& k : known)
            if (lower(k).find(n) != std::string::npos) found.push_back({k.size(), k});
    if (found.empty()) return {};
    const size_t shortest =
        std::min_element(
            found.begin(), found.end(), [](auto& a, auto& b) { return a.first < b.first; })
            ->first;
    found.erase(
        std::remove_if(
            found.begin(), found.end(), [&](const auto& f) { return f.first > shortest + 3; }),
        found.end());
    return bestThree(std::move(found));
}

/** keyExists(), without regard to case as MRPT reads keys. */
bool hasKey(
    const mrpt::config::CConfigFileBase& ini, const std::string& section, const std::string& key)
{
    std::vector<std::string> keys;
    ini.getAllKeys(section, keys);
    return std::any_of(keys.begin(), keys.end(), [&](const auto& k) { return sameName(k, key); });
}

/** Keys every generic sensor section has: MRPT's CGenericSensor::loadConfig reads four, the
 *  programs that run sensors (rawlog-grabber, wifi-localize) the other two. */
std::vector<Key> genericSensorKeys()
{
    return {
        {"driver", ReadBy::Program},       {"rawlog-grabber-ignore", ReadBy::Program},
        {"process_rate", ReadBy::Mrpt},    {"max_queue_len", ReadBy::Mrpt},
        {"grab_decimation", ReadBy::Mrpt}, {"sensorLabel", ReadBy::Mrpt},
    };
}

std::vector<Key> sectionKeysOf(std::initializer_list<const char*> names)
{
    std::vector<Key> keys;
    for (const char* n : names) keys.push_back({n, ReadBy::Section});
    return keys;
}

std::vector<SectionKeys> makeRegistry()
{
    std::vector<SectionKeys> r;

    SectionKeys csi{"CWiFiCSISensor", "a CWiFiCSISensor section (driver = CWiFiCSISensor)", {}, {}};
    csi.keys = genericSensorKeys();
    for (auto& k : sectionKeysOf(
             {// pose of the receive array on the robot (m, deg)
              "pose_x", "pose_y", "pose_z", "pose_yaw", "pose_pitch", "pose_roll",
              // data path
              "source", "udp_bind_address", "udp_port", "udp_receive_buffer", "pcap_file",
              "pcap_speed", "serial_baud", "router_address", "mac_filter", "min_rssi_dBm", "format",
              "overwritten_bins", "frame_timeout", "core_mask", "stream_mask", "status_period",
              "abort_on_error", "record_chain_states",
              // control path: WiROS's 'login', 'channel', 'packet', 'setup' groups
              "router_control", "login_host", "login_port", "login_user", "login_identity_file",
              "login_known_hosts", "login_accept_new_host_key", "login_password_env",
              "login_askpass", "login_connect_timeout", "ssh_persistent_session", "command_timeout",
              "setup_load_module", "setup_module_path", "setup_bridge", "setup_interface_5g",
              "setup_interface_2g4", "channel", "packet_mac_filter", "packet_delay",
              "packet_first_byte",
              // Raspberry Pi control
              "pi_control", "pi_interface", "pi_monitor_interface", "pi_tool_dir",
              // transmitter mode
              "transmitter_mode", "transmitter_mac", "transmitter_rate_hz", "transmitter_streams",
              "transmitter_count",
              // scanning and automatic channel
              "scan_period", "scan_wait", "scanner", "scan_interface", "auto_channel",
              "auto_min_rssi_gain_dB", "auto_min_dwell_s", "auto_min_rssi_dBm", "auto_ssid",
              "auto_mac_filter",
              // channel hopping
              "channel_schedule", "channel_dwell_s",
              // bearings computed live
              "bearing_algorithm", "bearing_calibration", "bearing_array", "bearing_options",
              "bearing_tx_arrays", "bearing_queue_length", "bearing_calibration_max_age_days"}))
        csi.keys.push_back(k);
    r.push_back(csi);

    SectionKeys odo{
        "CWiFiOdometryUdpSensor",
        "a CWiFiOdometryUdpSensor section (driver = CWiFiOdometryUdpSensor)",
        genericSensorKeys(),
        {}};
    for (auto& k : sectionKeysOf({"udp_port", "udp_bind_address"})) odo.keys.push_back(k);
    r.push_back(odo);

    SectionKeys live{"wifi-localize", "section 'wifi-localize'", {}, {}};
    live.keys = sectionKeysOf(
        {"max_bearings_per_step", "max_queue_s", "bearing_bias_std_deg", "map_devices",
         "map_min_std_deg", "map_outlier_prob", "map_loss", "map_grid_m", "map_update_period_s",
         "map_odometry_drift_xy", "map_odometry_drift_yaw_deg"});
    // wifi-localize's main: its own bearing chain, and how long it waits for CSI.
    for (const char* k :
         {"bearing_algorithm", "bearing_array", "bearing_calibration", "bearing_tx_arrays",
          "bearing_stride", "no_csi_timeout_s"})
        live.keys.push_back({k, ReadBy::Program});
    live.formerKeys = {
        // One name across programs: the sensor's, which takes a list as this one now does.
        {"bearing_tx_array", "bearing_tx_arrays", ""},
        // The live filter's random walk, replaced by the unknown-motion model both filters use.
        {"unknown_motion_speed_mps", "max_speed_mps", "UnknownMotion"},
        {"unknown_motion_turn_dps", "max_turn_rate_dps", "UnknownMotion"}};
    r.push_back(live);

    r.push_back(
        {"UnknownMotion",
         "section 'UnknownMotion'",
         sectionKeysOf(
             {"max_speed_mps", "max_turn_rate_dps", "correlation_time_s", "max_step_s",
              "min_std_xy", "min_std_phi_deg", "constant_velocity", "velocity_window_s",
              "forward_only", "wide_fraction", "wide_correlation_time_s", "bearing_weight"}),
         {}});
    r.push_back(
        {"OdometryMotion",
         "section 'OdometryMotion'",
         sectionKeysOf(
             {"std_xy_per_sqrt_m", "std_phi_deg_per_sqrt_m", "std_xy_per_sqrt_s",
              "std_phi_deg_per_sqrt_s", "max_step_s", "jump_rate_hz", "jump_std_xy_m",
              "jump_std_phi_deg", "bearing_weight"}),
         {}});
    r.push_back(
        {"ParticleRecovery",
         "section 'ParticleRecovery'",
         sectionKeysOf({"rate_hz", "window_s", "min_agreement", "max_std_deg"}),
         {}});
    r.push_back(
        {"WindowSmoother",
         "section 'WindowSmoother'",
         sectionKeysOf(
             {"enabled",
              "window_s",
              "min_window_s",
              "solve_period_s",
              "max_median_whitened_residual",
              "max_filter_spread_m",
              "max_recent_residual_deg",
              "node_period_s",
              "odometry_scale_std",
              "odometry_yaw_drift_deg_per_m",
              "min_std_deg",
              "loss",
              "bearing_decorrelation_m",
              "max_iterations",
              "without_odometry",
              "track_window_s",
              "track_switch_cost",
              "track_restart_headings",
              "track_node_period_s",
              "track_accel_std",
              "track_turn_accel_std_deg",
              "track_lateral_std_m"}),
         {}});
    r.push_back(
        {"MetricMap_wifiBearingMap_NN_creationOpts",
         "section 'MetricMap_wifiBearingMap_NN_creationOpts'",
         sectionKeysOf({"transmitters_file", "min_x", "max_x", "min_y", "max_y"}),
         {}});
    // MRPT's TMapGenericParams, which every map reads from its creationOpts.
    for (const char* k :
         {"enableSaveAs3DObject", "enableObservationLikelihood", "enableObservationInsertion"})
        r.back().keys.push_back({k, ReadBy::Mrpt});
    r.push_back(
        {"MetricMap_wifiBearingMap_NN_likelihoodOpts",
         "section 'MetricMap_wifiBearingMap_NN_likelihoodOpts'",
         sectionKeysOf(
             {"use_aoa", "use_aod", "outlier_prob", "min_std_deg", "max_std_deg", "std_scale",
              "aoa_alternative_share", "bearing_weight"}),
         {}});
    return r;
}

/** "section 'MetricMap_wifiBearingMap_00_likelihoodOpts'" for a key of the likelihood section
 *  found while checking [MetricMap_wifiBearingMap_00_creationOpts]: the user's own map number. */
std::string titleFor(const SectionKeys& kind, const std::string& checkedSection)
{
    const auto idAt = kind.id.find("_NN_");
    const auto titleAt = kind.title.find("_NN_");
    if (idAt == std::string::npos || titleAt == std::string::npos) return kind.title;
    const std::string prefix = kind.id.substr(0, idAt + 1);  // "MetricMap_wifiBearingMap_"
    if (checkedSection.size() <= prefix.size() ||
        !sameName(checkedSection.substr(0, prefix.size()), prefix))
        return kind.title;
    size_t end = prefix.size();
    while (end < checkedSection.size() &&
           std::isdigit(static_cast<unsigned char>(checkedSection[end])))
        ++end;
    if (end == prefix.size()) return kind.title;
    std::string t = kind.title;
    t.replace(titleAt + 1, 2, checkedSection.substr(prefix.size(), end - prefix.size()));
    return t;
}

std::string quotedList(const std::vector<std::string>& names)
{
    std::string s;
    for (size_t i = 0; i < names.size(); ++i)
        s += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + ("'" + names[i] + "'");
    return s;
}
}  // namespace

bool SectionKeys::has(const std::string& key) const
{
    for (const auto& k : keys)
        if (sameName(k.name, key)) return true;
    return false;
}

std::vector<std::string> SectionKeys::names() const
{
    std::vector<std::string> n;
    for (const auto& k : keys) n.push_back(k.name);
    return n;
}

const std::vector<SectionKeys>& projectSections()
{
    static const std::vector<SectionKeys> registry = makeRegistry();
    return registry;
}

const SectionKeys& sectionKeys(const std::string& id)
{
    for (const auto& s : projectSections())
        if (s.id == id) return s;
    throw std::logic_error("config::sectionKeys: no section kind '" + id + "' in the registry");
}

bool sectionMatches(const std::string& id, const std::string& section)
{
    const auto nn = id.find("_NN_");
    if (nn == std::string::npos) return sameName(id, section);
    const std::string head = id.substr(0, nn + 1), tail = id.substr(nn + 3);
    if (section.size() <= head.size() + tail.size()) return false;
    const std::string middle =
        section.substr(head.size(), section.size() - head.size() - tail.size());
    return sameName(section.substr(0, head.size()), head) &&
           sameName(section.substr(section.size() - tail.size()), tail) && !middle.empty() &&
           std::all_of(middle.begin(), middle.end(), [](char c) { return c >= '0' && c <= '9'; });
}

size_t editDistance(const std::string& a, const std::string& b)
{
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i)
    {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j)
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] != b[j - 1])});
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

std::vector<std::string> likelyMeant(const std::string& name, const std::vector<std::string>& known)
{
    auto meant = typosOf(name, known);
    return meant.empty() ? partsOf(name, known) : meant;
}

std::vector<std::string> checkSectionKeys(
    const mrpt::config::CConfigFileBase& ini, const std::string& section, const SectionKeys& kind)
{
    std::vector<std::string> notes;
    std::vector<std::string> present;
    ini.getAllKeys(section, present);
    const std::string where = "section '" + section + "': ";
    for (const auto& key : present)
    {
        if (kind.has(key)) continue;
        const std::string unknown = where + "unknown key '" + key + "'";
        // A former name.
        const auto former = std::find_if(
            kind.formerKeys.begin(), kind.formerKeys.end(),
            [&](const FormerKey& f) { return sameName(f.oldName, key); });
        if (former != kind.formerKeys.end())
        {
            if (former->newSection.empty())
            {
                if (hasKey(ini, section, former->newName))
                    throw std::invalid_argument(
                        where + "'" + key + "' and '" + former->newName +
                        "' are the same key (renamed to '" + former->newName + "'): keep only '" +
                        former->newName + "'");
                notes.push_back(
                    where + "'" + key + "' is now called '" + former->newName +
                    "' (read as such; rename it to silence this note)");
                continue;
            }
            throw std::invalid_argument(
                unknown + ": it is no longer read here; it is now '" + former->newName + "' in " +
                titleFor(sectionKeys(former->newSection), section));
        }
        const auto meantHere = [&](const std::vector<std::string>& meant)
        { throw std::invalid_argument(unknown + " (did you mean " + quotedList(meant) + "?)"); };
        // A typo of one of this section's keys.
        if (const auto meant = typosOf(key, kind.names()); !meant.empty()) meantHere(meant);
        // A key of another section, exactly.
        std::vector<std::string> owners;
        for (const auto& other : projectSections())
            if (&other != &kind && other.has(key)) owners.push_back(titleFor(other, section));
        if (!owners.empty())
        {
            std::string list;
            for (size_t i = 0; i < owners.size(); ++i)
                list += (i == 0 ? "" : i + 1 == owners.size() ? " or " : ", ") + owners[i];
            throw std::invalid_argument(unknown + ": it belongs in " + list);
        }
        // A part of one of this section's keys.
        if (const auto meant = partsOf(key, kind.names()); !meant.empty()) meantHere(meant);
        // A typo or a part of another section's key.
        for (const auto& other : projectSections())
        {
            if (&other == &kind) continue;
            if (const auto meant = likelyMeant(key, other.names()); !meant.empty())
                throw std::invalid_argument(
                    unknown + " (did you mean " + quotedList(meant) + " in " +
                    titleFor(other, section) + "?)");
        }
        throw std::invalid_argument(
            unknown + "; the keys of " + kind.title + " are listed in docs/configuration.md");
    }
    return notes;
}

void requireKnownKeys(
    const mrpt::config::CConfigFileBase& ini, const std::string& section, const SectionKeys& keys,
    std::ostream& out)
{
    for (const auto& n : checkSectionKeys(ini, section, keys)) out << "note: " << n << "\n";
}

void requireKnownKeys(
    const mrpt::config::CConfigFileBase& ini, const std::string& section, const SectionKeys& keys)
{
    requireKnownKeys(ini, section, keys, std::cerr);
}

const std::vector<std::string>& pfLocalizationMrptSections()
{
    static const std::vector<std::string> sections = {
        "LocalizationExperiment", "PF_options", "KLD_options",
        "DummyOdometryParams",    "MetricMap",  "MetricMap_*"};
    return sections;
}

std::vector<std::string> unreadSections(
    const mrpt::config::CConfigFileBase& ini, const std::vector<std::string>& mrptSections)
{
    // Names a misspelt section may have meant: the project's (a map's as number 00) and MRPT's.
    std::vector<std::string> candidates;
    for (const auto& k : projectSections())
        if (k.id.find("_NN_") != std::string::npos)
            candidates.push_back(
                k.id.substr(0, k.id.find("_NN_")) + "_00_" + k.id.substr(k.id.find("_NN_") + 4));
        else if (!k.has("driver"))  // a sensor's section has the user's name
            candidates.push_back(k.id);
    for (const auto& m : mrptSections)
        if (m.empty() || m.back() != '*') candidates.push_back(m);

    const std::string ownMapPrefix = "metricmap_wifibearingmap_";
    std::vector<std::string> sections, warnings;
    ini.getAllSections(sections);
    for (const auto& section : sections)
    {
        if (section.empty() || hasKey(ini, section, "driver")) continue;
        const bool project = std::any_of(
            projectSections().begin(), projectSections().end(),
            [&](const SectionKeys& k) { return sectionMatches(k.id, section); });
        if (project) continue;
        const bool mrpt = std::any_of(
            mrptSections.begin(), mrptSections.end(),
            [&](const std::string& m)
            {
                if (m.empty() || m.back() != '*') return sameName(m, section);
                const std::string prefix = lower(m.substr(0, m.size() - 1));
                return lower(section).rfind(prefix, 0) == 0 &&
                       lower(section).rfind(ownMapPrefix, 0) != 0;
            });
        if (mrpt) continue;
        const auto meant = likelyMeant(section, candidates);
        warnings.push_back(
            "section '" + section + "' is not read by this program" +
            (meant.empty() ? std::string(" (its keys have no effect)")
                           : " (did you mean " + quotedList(meant) + "?)"));
    }
    return warnings;
}

std::string readString(
    const mrpt::config::CConfigFileBase& ini, const std::string& section, const SectionKeys& kind,
    const std::string& key, const std::string& defaultValue)
{
    if (hasKey(ini, section, key)) return ini.read_string(section, key, defaultValue);
    for (const auto& f : kind.formerKeys)
        if (f.newSection.empty() && sameName(f.newName, key) && hasKey(ini, section, f.oldName))
            return ini.read_string(section, f.oldName, defaultValue);
    return ini.read_string(section, key, defaultValue);
}

}  // namespace mrpt_wifi::config
