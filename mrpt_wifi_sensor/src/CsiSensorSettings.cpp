/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt/system/string_utils.h>
#include <mrpt_wifi/obs/ConfigKeys.h>
#include <mrpt_wifi/obs/ConfigPaths.h>
#include <mrpt_wifi/sensor/CsiLiveSource.h>
#include <mrpt_wifi/sensor/CsiSensorSettings.h>

#include <algorithm>

namespace mrpt_wifi
{
namespace
{
unsigned parseUnsigned(const std::string& text, const std::string& key, unsigned maxValue)
{
    try
    {
        size_t used = 0;
        const unsigned long v = std::stoul(text, &used, 0);  // 0x.. accepted
        if (used == text.size() && v <= maxValue) return unsigned(v);
    }
    catch (const std::exception&)
    {
    }
    throw std::invalid_argument(
        "key '" + key + "': '" + text + "' is not a number in 0.." + std::to_string(maxValue));
}

std::vector<std::string> splitList(const std::string& s)
{
    std::vector<std::string> parts;
    mrpt::system::tokenize(s, ", \t", parts);
    return parts;
}
}  // namespace

CsiSensorSettings loadCsiSensorSettings(
    const mrpt::config::CConfigFileBase& c, const std::string& section,
    const std::string& sensorLabel)
{
    CsiSensorSettings settings;
    // Unknown keys: named with the key meant (a typo, another name, another section).
    config::requireKnownKeys(c, section, config::sectionKeys("CWiFiCSISensor"));

    auto& s = settings;
    const auto str = [&](const std::string& key, const std::string& def)
    { return mrpt::system::trim(c.read_string(section, key, def)); };
    try
    {
        s.assembler.sensorLabel = sensorLabel;
        s.assembler.sensorPose = mrpt::poses::CPose3D(
            c.read_double(section, "pose_x", 0), c.read_double(section, "pose_y", 0),
            c.read_double(section, "pose_z", 0),
            mrpt::DEG2RAD(c.read_double(section, "pose_yaw", 0)),
            mrpt::DEG2RAD(c.read_double(section, "pose_pitch", 0)),
            mrpt::DEG2RAD(c.read_double(section, "pose_roll", 0)));

        const std::string source = str("source", "udp");
        if (source == "udp")
            s.source = CsiSensorSettings::Source::Udp;
        else if (source == "pcap")
            s.source = CsiSensorSettings::Source::Pcap;
        else if (isLiveSourceSpec(source))
        {
            s.source = CsiSensorSettings::Source::Live;
            s.liveSource = source;
        }
        else
            throw std::invalid_argument(
                "key 'source': '" + source +
                "' (expected udp, pcap, interface:IFACE or serial:DEVICE)");
        s.serialBaud =
            unsigned(parseUnsigned(str("serial_baud", "921600"), "serial_baud", 4000000));
        s.udp.bindAddress = str("udp_bind_address", "0.0.0.0");
        s.udp.port = uint16_t(parseUnsigned(str("udp_port", "5500"), "udp_port", 65535));
        s.udp.receiveBufferBytes = int(
            parseUnsigned(str("udp_receive_buffer", "16777216"), "udp_receive_buffer", 1u << 30));
        s.pcapFile = str("pcap_file", "");
        if (s.source == CsiSensorSettings::Source::Pcap && s.pcapFile.empty())
            throw std::invalid_argument("source = pcap needs key 'pcap_file'");
        s.pcapSpeed = c.read_double(section, "pcap_speed", 1.0);
        if (!(s.pcapSpeed > 0)) throw std::invalid_argument("key 'pcap_speed' must be > 0");
        s.routerAddress = str("router_address", "");
        s.macFilter.clear();
        for (const auto& p : splitList(str("mac_filter", "")))
            s.macFilter.push_back(MacPattern::fromString(p));
        s.minRssi_dBm = c.read_int(section, "min_rssi_dBm", -128);
        s.assembler.format = nexmon::formatHintFromString(str("format", "auto"));
        s.assembler.overwrittenBins =
            overwrittenBinPolicyFromString(str("overwritten_bins", "repair"));
        s.assembler.frameTimeout_s = c.read_double(section, "frame_timeout", 0.1);
        const std::string piControl = str("pi_control", "off");
        if (piControl == "local")
            s.piControl = CsiSensorSettings::PiControl::Local;
        else if (piControl == "ssh")
            s.piControl = CsiSensorSettings::PiControl::Ssh;
        else if (piControl != "off")
            throw std::invalid_argument(
                "key 'pi_control': '" + piControl + "' (expected off, local or ssh)");
        // The Pi's bcm43455c0 has one core and reports one stream.
        const char* maskDefault = s.piControl != CsiSensorSettings::PiControl::Off ? "0x1" : "0xf";
        s.assembler.coreMask =
            uint8_t(parseUnsigned(str("core_mask", maskDefault), "core_mask", 0xF));
        s.assembler.streamMask =
            uint8_t(parseUnsigned(str("stream_mask", maskDefault), "stream_mask", 0xF));
        s.statusPeriod_s = c.read_double(section, "status_period", 10.0);
        s.abortOnError = c.read_bool(section, "abort_on_error", false);
        s.recordChainStates = c.read_bool(section, "record_chain_states", true);

        s.routerControl = c.read_bool(section, "router_control", false);
        s.ssh.host = str("login_host", s.ssh.host);
        s.ssh.port = parseUnsigned(str("login_port", "22"), "login_port", 65535);
        s.ssh.user = str("login_user", s.ssh.user);
        s.ssh.identityFile = str("login_identity_file", "");
        s.ssh.knownHostsFile = str("login_known_hosts", "");
        s.ssh.acceptNewHostKey = c.read_bool(section, "login_accept_new_host_key", false);
        s.ssh.passwordEnvVar = str("login_password_env", "");
        s.ssh.askpassProgram = str("login_askpass", "");
        s.ssh.connectTimeout_s = c.read_double(section, "login_connect_timeout", 5.0);
        s.ssh.persistentSession = c.read_bool(section, "ssh_persistent_session", true);
        s.setup.commandTimeout_s = c.read_double(section, "command_timeout", 10.0);
        s.loadModule = c.read_bool(section, "setup_load_module", true);
        s.setup.modulePath = str("setup_module_path", s.setup.modulePath);
        s.setup.bridge = str("setup_bridge", s.setup.bridge);
        s.setup.interface5G = str("setup_interface_5g", s.setup.interface5G);
        s.setup.interface2G4 = str("setup_interface_2g4", s.setup.interface2G4);
        s.setup.scanWait_s = c.read_double(section, "scan_wait", 3.0);
        s.setup.validate();
        try
        {
            s.extraction.chanspec = Chanspec::fromString(str("channel", "157/80"));
        }
        catch (const std::invalid_argument& e)
        {
            throw std::invalid_argument(std::string("key 'channel': ") + e.what());
        }
        s.extraction.coreMask = s.assembler.coreMask;
        s.extraction.streamMask = s.assembler.streamMask;
        s.extraction.macFilter.clear();
        for (const auto& m : splitList(str("packet_mac_filter", "")))
            s.extraction.macFilter.push_back(MacAddress::fromString(m));
        if (s.extraction.macFilter.size() > 4)
            throw std::invalid_argument(
                "key 'packet_mac_filter': the firmware takes at most 4 MACs");
        s.extraction.delay =
            uint16_t(parseUnsigned(str("packet_delay", "0"), "packet_delay", 0xFFFF));
        if (const auto b = str("packet_first_byte", ""); !b.empty())
            s.extraction.firstPacketByte = uint8_t(parseUnsigned(b, "packet_first_byte", 0xFF));

        if (s.piControl != CsiSensorSettings::PiControl::Off)
        {
            if (s.routerControl)
                throw std::invalid_argument(
                    "router_control and pi_control both set: one device configures the capture");
            s.pi.interface = str("pi_interface", s.pi.interface);
            s.pi.monitorInterface = str("pi_monitor_interface", s.pi.monitorInterface);
            s.pi.toolDir = str("pi_tool_dir", "");
            s.pi.commandTimeout_s = s.setup.commandTimeout_s;
            s.pi.validate();
            validatePiExtraction(s.extraction);
        }
        else
            for (const char* k : {"pi_interface", "pi_monitor_interface", "pi_tool_dir"})
                if (!str(k, "").empty())
                    throw std::invalid_argument(
                        std::string("key '") + k + "' needs pi_control = local or ssh");

        s.transmitterMode = c.read_bool(section, "transmitter_mode", false);
        if (const auto m = str("transmitter_mac", ""); !m.empty())
            s.transmitter.source = MacAddress::fromString(m);
        s.transmitter.rate_Hz = c.read_double(section, "transmitter_rate_hz", 50.0);
        s.transmitter.streams =
            parseUnsigned(str("transmitter_streams", "1"), "transmitter_streams", 4);
        s.transmitter.count =
            parseUnsigned(str("transmitter_count", "1000"), "transmitter_count", 10000000);

        s.scanPeriod_s = c.read_double(section, "scan_period", 0.0);
        const std::string scanner = str("scanner", "router");
        if (scanner != "router" && scanner != "host")
            throw std::invalid_argument(
                "key 'scanner': '" + scanner + "' (expected router or host)");
        s.scanWithHost = scanner == "host";
        s.scanInterface = str("scan_interface", "wlan0");
        s.autoChannel = c.read_bool(section, "auto_channel", false);
        s.autoMacFilter = c.read_bool(section, "auto_mac_filter", true);
        s.selector.minRssiGain_dB = c.read_double(section, "auto_min_rssi_gain_dB", 6.0);
        s.selector.minDwell_s = c.read_double(section, "auto_min_dwell_s", 10.0);
        s.selector.minRssi_dBm = c.read_int(section, "auto_min_rssi_dBm", -85);
        s.selector.ssidFilter = str("auto_ssid", "");
        if ((s.autoChannel || (s.scanPeriod_s > 0 && !s.scanWithHost) || s.transmitterMode) &&
            !s.routerControl)
            throw std::invalid_argument(
                "auto_channel, transmitter_mode and router-side scans (scan_period with scanner = "
                "router) need router_control = true");
        auto& b = s.bearing;
        b.algorithm = str("bearing_algorithm", "");
        b.calibration = str("bearing_calibration", "");
        b.arrayFile = str("bearing_array", "");
        b.optionsFile = str("bearing_options", "");
        b.txArrays = splitList(str("bearing_tx_arrays", ""));
        b.queueLength =
            parseUnsigned(str("bearing_queue_length", "64"), "bearing_queue_length", 100000);
        if (b.queueLength == 0)
            throw std::invalid_argument("key 'bearing_queue_length' must be at least 1");
        b.calibrationMaxAge_days = c.read_double(section, "bearing_calibration_max_age_days", 7.0);
        if (!b.enabled())
            for (const char* k :
                 {"bearing_calibration", "bearing_array", "bearing_options", "bearing_tx_arrays"})
                if (!str(k, "").empty())
                    throw std::invalid_argument(
                        std::string("key '") + k + "' needs bearing_algorithm (bearings are off)");
        if (s.autoChannel && !(s.scanPeriod_s > 0))
            throw std::invalid_argument("auto_channel = true needs scan_period > 0");
        // Channel hopping (as WiROS's CSI node's channel service: the same configuration
        // commands, one channel after the other).
        const std::string schedule = str("channel_schedule", "");
        s.channelDwell_s = c.read_double(section, "channel_dwell_s", 2.0);
        if (schedule == "scan")
            s.scheduleFromScan = true;
        else
            for (const auto& item : splitList(schedule))
            {
                Chanspec cs;
                try
                {
                    cs = Chanspec::fromString(item);
                }
                catch (const std::invalid_argument& e)
                {
                    throw std::invalid_argument(
                        "key 'channel_schedule': '" + item + "': " + e.what() +
                        " (expected a list such as '42/80 155/80 6/20', or 'scan')");
                }
                for (const auto& seen : s.channelSchedule)
                    if (seen.sameChannel(cs))
                        throw std::invalid_argument(
                            "key 'channel_schedule': " + cs.asString() + " is listed twice");
                s.channelSchedule.push_back(cs);
            }
        if (s.hopping())
        {
            if (s.autoChannel)
                throw std::invalid_argument(
                    "channel_schedule and auto_channel = true both decide the channel: set "
                    "auto_channel = false to hop among channels, or remove channel_schedule to "
                    "follow the strongest access point");
            if (!s.routerControl)
                throw std::invalid_argument(
                    "channel_schedule needs router_control = true (the router is retuned over "
                    "ssh)");
            if (s.transmitterMode)
                throw std::invalid_argument(
                    "channel_schedule and transmitter_mode cannot be combined (the transmitter "
                    "sends on one channel)");
            if (s.scheduleFromScan && !(s.scanPeriod_s > 0))
                throw std::invalid_argument(
                    "channel_schedule = scan needs scan_period > 0 (the scans give the channels)");
            if (!(s.channelDwell_s > 0))
                throw std::invalid_argument("key 'channel_dwell_s' must be > 0");
            // A given schedule starts on its first channel.
            if (!s.channelSchedule.empty()) s.extraction.chanspec = s.channelSchedule.front();
        }
        else if (!str("channel_dwell_s", "").empty())
            throw std::invalid_argument("key 'channel_dwell_s' needs channel_schedule");
        // Files named here: from this .ini's folder (rawlog-grabber's file found on its command
        // line), arrays also by name from the data folder (mrpt_wifi/obs/ConfigPaths.h).
        const std::string iniDir = config::iniDirectory(c, section);
        const auto resolve = [&](std::string& value, const char* key, const char* kind)
        {
            auto r =
                config::resolveConfigPath(value, iniDir, kind, std::string("key '") + key + "'");
            if (!r.note.empty()) s.pathNotes.push_back(r.note);
            value = r.path;
        };
        if (s.source == CsiSensorSettings::Source::Pcap)
            resolve(s.pcapFile, "pcap_file", "samples");
        // The ssh key by the same rule; one not found is left as written, for ssh to report.
        try
        {
            resolve(s.ssh.identityFile, "login_identity_file", "");
        }
        catch (const std::invalid_argument&)
        {
        }
        if (b.enabled())
        {
            resolve(b.calibration, "bearing_calibration", "");
            resolve(b.arrayFile, "bearing_array", "arrays");
            if (!b.optionsFile.empty() && b.optionsFile.front() != '{')
                resolve(b.optionsFile, "bearing_options", "bearings");
            b.txArrays = config::resolveConfigPathList(
                b.txArrays, iniDir, "arrays", "key 'bearing_tx_arrays'", &s.pathNotes);
        }
    }
    catch (const std::invalid_argument& e)
    {
        throw std::invalid_argument("section '" + section + "': " + e.what());
    }
    return settings;
}

}  // namespace mrpt_wifi
