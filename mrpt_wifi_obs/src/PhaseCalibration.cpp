/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/containers/yaml.h>
#include <mrpt_wifi/obs/PhaseCalibration.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace mrpt_wifi
{
namespace fs = std::filesystem;

namespace
{
[[noreturn]] void fail(const std::string& where, const std::string& what)
{
    throw CalibrationError("phase calibration " + where + ": " + what);
}

mrpt::containers::yaml required(
    const mrpt::containers::yaml& doc, const std::string& key, const std::string& where)
{
    if (!doc.has(key)) fail(where, "missing key '" + key + "'");
    return doc[key];
}

template <class T>
T asValue(const mrpt::containers::yaml& node, const std::string& key, const std::string& where)
{
    try
    {
        return node.as<T>();
    }
    catch (const std::exception&)
    {
        fail(where, "key '" + key + "' has the wrong type");
    }
}

/** A YAML single-quoted scalar ('' escapes a quote). */
std::string quoted(const std::string& s)
{
    std::string o = "'";
    for (char c : s) o += c == '\'' ? std::string("''") : std::string(1, c);
    return o + "'";
}

std::vector<double> numberList(
    const mrpt::containers::yaml& node, const std::string& key, const std::string& where)
{
    if (!node.isSequence()) fail(where, "'" + key + "' must be a list of numbers");
    std::vector<double> v;
    v.reserve(node.asSequence().size());
    for (const auto& e : node.asSequence()) v.push_back(asValue<double>(e, key, where));
    return v;
}
}  // namespace

PhaseCalibration PhaseCalibration::fromYamlFile(const std::string& path)
{
    std::ifstream f(path);
    if (!f) throw CalibrationError("phase calibration '" + path + "': cannot open the file");
    std::stringstream ss;
    ss << f.rdbuf();
    PhaseCalibration c = fromYamlText(ss.str(), "'" + path + "'");
    c.sourcePath = path;
    return c;
}

PhaseCalibration PhaseCalibration::fromYamlText(
    const std::string& text, const std::string& displayName)
{
    const std::string& w = displayName;
    mrpt::containers::yaml doc;
    try
    {
        doc = mrpt::containers::yaml::FromText(text);
    }
    catch (const std::exception& e)
    {
        fail(w, std::string("not valid YAML: ") + e.what());
    }
    if (!doc.isMap()) fail(w, "expected a YAML map");
    static const char* known[] = {
        "format",
        "version",
        "device",
        "chanspec",
        "date",
        "frames_used",
        "residual_rad",
        "method",
        "antennas",
        "subcarriers",
        "phases_rad",
        "gains_db",
        "subband_sign_corrected",
        "role",
        "transmitter",
        "aod_residual_rad",
        "chain_states",
        "chain_state_tolerance_ns",
        "chain_states_delay_only"};
    for (const auto& kv : doc.asMap())
    {
        const std::string key = kv.first.as<std::string>();
        if (std::find(std::begin(known), std::end(known), key) == std::end(known))
            fail(w, "unknown key '" + key + "'");
    }
    if (asValue<std::string>(required(doc, "format", w), "format", w) !=
        "mrpt_wifi_phase_calibration")
        fail(w, "'format' is not mrpt_wifi_phase_calibration");
    const int version = asValue<int>(required(doc, "version", w), "version", w);
    if (version < 1 || version > kFormatVersion)
        fail(
            w, "version " + std::to_string(version) + " is not supported (expected 1 to " +
                   std::to_string(kFormatVersion) + ")");
    if (version < 2)
        for (const char* k : {"role", "transmitter", "aod_residual_rad"})
            if (doc.has(k)) fail(w, std::string("key '") + k + "' needs version 2");
    if (version < 3)
        for (const char* k :
             {"chain_states", "chain_state_tolerance_ns", "chain_states_delay_only"})
            if (doc.has(k)) fail(w, std::string("key '") + k + "' needs version 3");

    PhaseCalibration c;
    if (doc.has("role"))
    {
        const std::string role = asValue<std::string>(doc["role"], "role", w);
        if (role == "transmitter")
            c.role = Role::Transmitter;
        else if (role != "receiver")
            fail(w, "role '" + role + "' is neither receiver nor transmitter");
    }
    if (c.role == Role::Transmitter)
    {
        const std::string mac =
            asValue<std::string>(required(doc, "transmitter", w), "transmitter", w);
        const auto parsed = MacAddress::parse(mac);
        if (!parsed) fail(w, "transmitter '" + mac + "' is not a MAC address");
        c.transmitter = *parsed;
        if (doc.has("aod_residual_rad"))
            c.aodResidual_rad = asValue<double>(doc["aod_residual_rad"], "aod_residual_rad", w);
    }
    else if (doc.has("transmitter") || doc.has("aod_residual_rad"))
        fail(w, "'transmitter' and 'aod_residual_rad' belong to role: transmitter");
    c.device = asValue<std::string>(required(doc, "device", w), "device", w);
    const std::string cs = asValue<std::string>(required(doc, "chanspec", w), "chanspec", w);
    try
    {
        c.chanspec = Chanspec::fromString(cs);
    }
    catch (const std::exception& e)
    {
        fail(w, "chanspec '" + cs + "': " + e.what());
    }
    if (doc.has("date")) c.date = asValue<std::string>(doc["date"], "date", w);
    if (doc.has("frames_used"))
        c.framesUsed = asValue<uint64_t>(doc["frames_used"], "frames_used", w);
    if (doc.has("residual_rad"))
        c.residual_rad = asValue<double>(doc["residual_rad"], "residual_rad", w);
    if (doc.has("method")) c.method = asValue<std::string>(doc["method"], "method", w);
    if (doc.has("subband_sign_corrected"))
        c.subbandSignCorrected =
            asValue<bool>(doc["subband_sign_corrected"], "subband_sign_corrected", w);
    for (double k : numberList(required(doc, "subcarriers", w), "subcarriers", w))
    {
        if (k != std::round(k)) fail(w, "subcarriers must be integers");
        c.subcarriers.push_back(int(k));
    }
    const auto& rows = required(doc, "phases_rad", w);
    if (!rows.isSequence()) fail(w, "'phases_rad' must be a list of per-antenna lists");
    for (const auto& r : rows.asSequence()) c.phases_rad.push_back(numberList(r, "phases_rad", w));
    if (doc.has("gains_db")) c.gains_dB = numberList(doc["gains_db"], "gains_db", w);
    if (doc.has("chain_state_tolerance_ns"))
        c.chainStateTolerance_s =
            asValue<double>(doc["chain_state_tolerance_ns"], "chain_state_tolerance_ns", w) * 1e-9;
    if (doc.has("chain_states_delay_only"))
        c.chainStatesDelayOnly =
            asValue<bool>(doc["chain_states_delay_only"], "chain_states_delay_only", w);
    if (doc.has("chain_states"))
    {
        const auto& states = doc["chain_states"];
        if (!states.isSequence()) fail(w, "'chain_states' must be a list of maps");
        for (const auto& node : states.asSequence())
        {
            const mrpt::containers::yaml e(node);
            if (!e.isMap()) fail(w, "every entry of 'chain_states' must be a map");
            for (const auto& kv : e.asMap())
            {
                const std::string key = kv.first.as<std::string>();
                static const char* knownState[] = {"antenna",        "state",           "delay_ns",
                                                   "delta_delay_ns", "delta_phase_rad", "frames"};
                if (std::find(std::begin(knownState), std::end(knownState), key) ==
                    std::end(knownState))
                    fail(w, "unknown key '" + key + "' in 'chain_states'");
            }
            ChainStateCalibration st;
            st.antenna = asValue<unsigned>(required(e, "antenna", w), "antenna", w);
            const unsigned id = asValue<unsigned>(required(e, "state", w), "state", w);
            if (id > 254) fail(w, "chain state ids must be 0..254");
            st.state = uint8_t(id);
            st.delay_s = asValue<double>(required(e, "delay_ns", w), "delay_ns", w) * 1e-9;
            st.deltaDelay_s =
                asValue<double>(required(e, "delta_delay_ns", w), "delta_delay_ns", w) * 1e-9;
            st.deltaPhase_rad =
                asValue<double>(required(e, "delta_phase_rad", w), "delta_phase_rad", w);
            if (e.has("frames")) st.frames = asValue<uint64_t>(e["frames"], "frames", w);
            c.chainStates.push_back(st);
        }
    }
    const size_t antennas = asValue<size_t>(required(doc, "antennas", w), "antennas", w);
    if (antennas != c.phases_rad.size())
        fail(
            w, "'antennas' says " + std::to_string(antennas) + " but 'phases_rad' has " +
                   std::to_string(c.phases_rad.size()) + " rows");
    c.validate(w);
    return c;
}

const ChainStateCalibration* PhaseCalibration::findChainState(unsigned antenna, uint8_t state) const
{
    for (const auto& st : chainStates)
        if (st.antenna == antenna && st.state == state) return &st;
    return nullptr;
}

const ChainStateCalibration* PhaseCalibration::matchChainState(
    unsigned antenna, double delay_s) const
{
    const ChainStateCalibration* best = nullptr;
    for (const auto& st : chainStates)
        if (st.antenna == antenna && std::abs(delay_s - st.delay_s) <= chainStateTolerance_s &&
            (!best || std::abs(delay_s - st.delay_s) < std::abs(delay_s - best->delay_s)))
            best = &st;
    return best;
}

void PhaseCalibration::validate(const std::string& where) const
{
    if (device.empty()) fail(where, "empty device name");
    if (!subbandSignCorrected)
        fail(
            where,
            "subband_sign_corrected: false is not supported; make the calibration on "
            "sign-corrected CSI");
    if (phases_rad.empty()) fail(where, "no antennas");
    if (subcarriers.empty()) fail(where, "no subcarriers");
    const int edge = int(chanspec.nfft() / 2);
    for (size_t j = 0; j < subcarriers.size(); ++j)
    {
        if (subcarriers[j] < -edge || subcarriers[j] >= edge)
            fail(
                where, "subcarrier " + std::to_string(subcarriers[j]) + " is outside ±" +
                           std::to_string(edge) + " for " + chanspec.asString());
        if (j > 0 && subcarriers[j] <= subcarriers[j - 1])
            fail(where, "subcarriers must be strictly ascending");
    }
    for (size_t i = 0; i < phases_rad.size(); ++i)
    {
        if (phases_rad[i].size() != subcarriers.size())
            fail(
                where, "phases_rad[" + std::to_string(i) + "] has " +
                           std::to_string(phases_rad[i].size()) + " values for " +
                           std::to_string(subcarriers.size()) + " subcarriers");
        for (double p : phases_rad[i])
            if (!std::isfinite(p)) fail(where, "phases_rad holds a non-finite value");
    }
    if (role == Role::Transmitter && (!std::isfinite(aodResidual_rad) || aodResidual_rad < 0))
        fail(where, "aod_residual_rad must be finite and >= 0");
    if (!(chainStateTolerance_s > 0) || !std::isfinite(chainStateTolerance_s))
        fail(where, "chain_state_tolerance_ns must be > 0");
    for (size_t a = 0; a < chainStates.size(); ++a)
    {
        const auto& st = chainStates[a];
        if (st.antenna < 1 || st.antenna >= phases_rad.size())
            fail(
                where, "chain_states: antenna " + std::to_string(st.antenna) +
                           " is not one of 1.." + std::to_string(phases_rad.size() - 1) +
                           " (antenna 0 is the reference)");
        if (!std::isfinite(st.delay_s) || !std::isfinite(st.deltaDelay_s) ||
            !std::isfinite(st.deltaPhase_rad))
            fail(where, "chain_states holds a non-finite value");
        for (size_t b = 0; b < a; ++b)
            if (chainStates[b].antenna == st.antenna && chainStates[b].state == st.state)
                fail(
                    where, "chain_states lists antenna " + std::to_string(st.antenna) + " state " +
                               std::to_string(int(st.state)) + " twice");
    }
    if (!gains_dB.empty() && gains_dB.size() != phases_rad.size())
        fail(
            where, "gains_db has " + std::to_string(gains_dB.size()) + " values for " +
                       std::to_string(phases_rad.size()) + " antennas");
}

std::string PhaseCalibration::asYamlText() const
{
    validate();
    std::ostringstream o;
    o.precision(10);
    o << "# mrpt_wifi phase calibration: CSI of antenna i at subcarrier k is multiplied by\n"
         "# exp(-j*phases_rad[i][k]) * 10^(-gains_db[i]/20) after the sub-band sign correction.\n";
    o << "format: mrpt_wifi_phase_calibration\n";
    // The lowest version that holds the content, so older readers still read what they can.
    o << "version: " << (chainStates.empty() && !chainStatesDelayOnly ? 2 : kFormatVersion) << "\n";
    if (role == Role::Transmitter)
        o << "role: transmitter\n"
          << "transmitter: '" << transmitter.asString() << "'\n"
          << "aod_residual_rad: " << aodResidual_rad << "\n";
    o << "device: " << device << "\n";
    o << "chanspec: " << chanspec.asString() << "\n";
    o << "date: " << quoted(date) << "\n";
    o << "frames_used: " << framesUsed << "\n";
    o << "residual_rad: " << residual_rad << "\n";
    o << "method: " << quoted(method) << "\n";
    o << "subband_sign_corrected: " << (subbandSignCorrected ? "true" : "false") << "\n";
    o << "antennas: " << phases_rad.size() << "\n";
    o << "subcarriers: [";
    for (size_t j = 0; j < subcarriers.size(); ++j) o << (j ? ", " : "") << subcarriers[j];
    o << "]\nphases_rad:\n";
    for (const auto& row : phases_rad)
    {
        o << "  - [";
        for (size_t j = 0; j < row.size(); ++j) o << (j ? ", " : "") << row[j];
        o << "]\n";
    }
    if (!gains_dB.empty())
    {
        o << "gains_db: [";
        for (size_t i = 0; i < gains_dB.size(); ++i) o << (i ? ", " : "") << gains_dB[i];
        o << "]\n";
    }
    if (chainStatesDelayOnly)
        o << "# the recording's jump states differ by a delay alone: the phases hold in each\n"
             "chain_states_delay_only: true\n";
    if (!chainStates.empty())
    {
        o << "# jump states: antenna i in state s is first multiplied by\n"
             "# exp(+j*2*pi*k*312.5e3*delta_delay) * exp(-j*delta_phase_rad)\n";
        o << "chain_state_tolerance_ns: " << chainStateTolerance_s * 1e9 << "\n";
        o << "chain_states:\n";
        for (const auto& st : chainStates)
            o << "  - antenna: " << st.antenna << "\n    state: " << int(st.state)
              << "\n    delay_ns: " << st.delay_s * 1e9
              << "\n    delta_delay_ns: " << st.deltaDelay_s * 1e9
              << "\n    delta_phase_rad: " << st.deltaPhase_rad << "\n    frames: " << st.frames
              << "\n";
    }
    return o.str();
}

void PhaseCalibration::saveYamlFile(const std::string& path) const
{
    const std::string text = asYamlText();
    std::error_code ec;
    const fs::path parent = fs::path(path).parent_path();
    if (!parent.empty()) fs::create_directories(parent, ec);
    std::ofstream f(path);
    if (!(f << text)) throw CalibrationError("phase calibration: cannot write '" + path + "'");
}

double PhaseCalibration::phaseAt(size_t antenna, int k) const
{
    const auto& row = phases_rad.at(antenna);
    const auto it = std::lower_bound(subcarriers.begin(), subcarriers.end(), k);
    if (it == subcarriers.end()) return row.back();
    const size_t j = size_t(it - subcarriers.begin());
    if (*it == k || j == 0) return row[j];
    // Interpolate on the shorter arc between the two neighbours.
    const double p0 = row[j - 1], p1 = row[j];
    const double d = std::remainder(p1 - p0, 2 * M_PI);
    const double t = double(k - subcarriers[j - 1]) / double(subcarriers[j] - subcarriers[j - 1]);
    return p0 + t * d;
}

bool PhaseCalibration::matchesChannel(const Chanspec& cs) const
{
    return cs.centerChannel == chanspec.centerChannel && cs.bandwidthMHz == chanspec.bandwidthMHz;
}

void PhaseCalibration::checkCompatible(
    const std::string& deviceName, const Chanspec& cs, size_t nRx) const
{
    const std::string src = sourcePath.empty() ? "" : " ('" + sourcePath + "')";
    if (device != deviceName)
        throw CalibrationError(
            "phase calibration" + src + " is for device '" + device +
            "', but the receiver's "
            "array is '" +
            deviceName + "'");
    if (!matchesChannel(cs))
        throw CalibrationError(
            "phase calibration" + src + " is for channel " + chanspec.asString() +
            ", but the CSI is on " + cs.asString() + ": calibrate that channel or pass a folder");
    if (antennas() < nRx)
        throw CalibrationError(
            "phase calibration" + src + " has " + std::to_string(antennas()) +
            " antennas, but the CSI has " + std::to_string(nRx) + " receive chains");
}

std::string PhaseCalibration::fileNameFor(const Chanspec& cs)
{
    return "ch" + std::to_string(cs.centerChannel) + "_" + std::to_string(cs.bandwidthMHz) +
           "mhz.yaml";
}

std::string PhaseCalibration::pathFor(
    const std::string& dir, const std::string& device, const Chanspec& cs)
{
    return (fs::path(dir) / device / fileNameFor(cs)).string();
}

std::string PhaseCalibration::transmitterPathFor(
    const std::string& dir, const MacAddress& mac, const Chanspec& cs)
{
    std::string m = mac.asString();
    std::replace(m.begin(), m.end(), ':', '-');
    return (fs::path(dir) / "transmitters" / m / fileNameFor(cs)).string();
}

CalibrationStore CalibrationStore::open(const std::string& fileOrDir)
{
    CalibrationStore s;
    s.path_ = fileOrDir;
    if (fs::is_directory(fileOrDir))
        s.dir_ = fileOrDir;
    else if (fs::is_regular_file(fileOrDir))
        s.single_ = std::make_shared<PhaseCalibration>(PhaseCalibration::fromYamlFile(fileOrDir));
    else
        throw CalibrationError("phase calibration '" + fileOrDir + "' does not exist");
    return s;
}

CalibrationStore CalibrationStore::fromCalibration(PhaseCalibration c)
{
    c.validate();
    CalibrationStore s;
    s.path_ = c.sourcePath.empty() ? "<in memory>" : c.sourcePath;
    s.single_ = std::make_shared<PhaseCalibration>(std::move(c));
    return s;
}

const PhaseCalibration* CalibrationStore::find(
    const std::string& device, const Chanspec& cs, size_t nRx) const
{
    if (single_)
    {
        if (single_->role == PhaseCalibration::Role::Transmitter)
            throw CalibrationError(
                "phase calibration '" + path_ +
                "' is a transmit-chain calibration: pass the calibration folder");
        single_->checkCompatible(device, cs, nRx);
        return single_.get();
    }
    if (dir_.empty()) return nullptr;
    const std::string p = PhaseCalibration::pathFor(dir_, device, cs);
    auto it = cache_.find(p);
    if (it == cache_.end())
    {
        std::shared_ptr<PhaseCalibration> c;
        if (fs::exists(p))
            c = std::make_shared<PhaseCalibration>(PhaseCalibration::fromYamlFile(p));
        if (c && c->role != PhaseCalibration::Role::Receiver)
            throw CalibrationError(
                "phase calibration '" + p + "' is a transmit-chain calibration, not a receiver's");
        it = cache_.emplace(p, c).first;
    }
    if (it->second) it->second->checkCompatible(device, cs, nRx);
    return it->second.get();
}

const PhaseCalibration* CalibrationStore::findTransmitter(
    const MacAddress& mac, const Chanspec& cs, size_t streams) const
{
    if (dir_.empty()) return nullptr;
    const std::string p = PhaseCalibration::transmitterPathFor(dir_, mac, cs);
    auto it = cache_.find(p);
    if (it == cache_.end())
    {
        std::shared_ptr<PhaseCalibration> c;
        if (fs::exists(p))
        {
            c = std::make_shared<PhaseCalibration>(PhaseCalibration::fromYamlFile(p));
            if (c->role != PhaseCalibration::Role::Transmitter || c->transmitter != mac)
                throw CalibrationError(
                    "phase calibration '" + p + "' is not the transmit-chain calibration of " +
                    mac.asString());
            if (!c->matchesChannel(cs))
                throw CalibrationError(
                    "phase calibration '" + p + "' is for channel " + c->chanspec.asString() +
                    ", not " + cs.asString());
        }
        it = cache_.emplace(p, c).first;
    }
    if (it->second && it->second->antennas() < streams)
        throw CalibrationError(
            "phase calibration '" + p + "' has " + std::to_string(it->second->antennas()) +
            " transmit chains, but " + mac.asString() + " sends " + std::to_string(streams) +
            " streams");
    return it->second.get();
}

std::vector<std::string> CalibrationStore::available(const std::string& device) const
{
    std::vector<std::string> out;
    if (single_)
    {
        out.push_back(single_->device + " " + single_->chanspec.asString());
        return out;
    }
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(fs::path(dir_) / device, ec))
        if (e.path().extension() == ".yaml") out.push_back(e.path().filename().string());
    std::sort(out.begin(), out.end());
    return out;
}

std::string CalibrationStore::missingChannelAdvice(
    const std::string& device, const Chanspec& cs) const
{
    std::string have;
    for (const auto& a : available(device)) have += (have.empty() ? "" : ", ") + a;
    if (have.empty()) have = "nothing for '" + device + "'";
    const std::string target = isFolder() ? PhaseCalibration::pathFor(dir_, device, cs)
                                          : "a folder, e.g. calib/" + device + "/";
    return "no calibration for " + cs.asString() + " in '" + path_ + "' (it has " + have +
           "): run wifi-calibrate on a drive among known access points with frames on " +
           cs.asString() +
           " (wifi-calibrate DRIVE.rawlog --array ARRAY --transmitters APS.yaml "
           "--out " +
           (isFolder() ? path_ : std::string("DIR")) + " writes " + target +
           ", one file per channel of the drive)";
}

}  // namespace mrpt_wifi
