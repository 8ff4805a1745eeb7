/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/math/geometry.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/sim/Scenario.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include "YamlReader.h"

namespace mrpt_wifi::sim
{
namespace detail
{
/** An inline array map {name, description, elements}, with errors at its YAML line (array
 * files go through AntennaArray::fromYamlFile). */
AntennaArray readAntennaArray(const YamlNode& n)
{
    n.allowOnly({"name", "description", "elements"});
    AntennaArray a;
    a.name = n.stringOr("name", "unnamed");
    a.description = n.stringOr("description", "");
    const YamlNode elems = n["elements"];
    if (!elems.isSequence() || elems.size() == 0)
        elems.fail("expected a non-empty list of [x, y] element positions in metres");
    for (size_t i = 0; i < elems.size(); ++i) a.elements.push_back(elems.at(i).asPoint2D());
    for (size_t i = 0; i < a.elements.size(); ++i)
        for (size_t j = 0; j < i; ++j)
            if (a.elements[i] == a.elements[j])
                elems.at(i).fail(
                    "element " + std::to_string(i) + " coincides with element " +
                    std::to_string(j));
    return a;
}
}  // namespace detail

using detail::YamlNode;
using mrpt::math::TPoint2D;

namespace
{
constexpr double kDeg = M_PI / 180.0;

std::string locate(const std::string& file, int line, const std::string& key)
{
    std::string s = file.empty() ? std::string("scenario") : file;
    if (line > 0) s += ":" + std::to_string(line);
    s += ": ";
    if (!key.empty()) s += key + ": ";
    return s;
}
}  // namespace

ScenarioError::ScenarioError(
    const std::string& file, int line, const std::string& keyPath, const std::string& message)
    : std::runtime_error(locate(file, line, keyPath) + message),
      file_(file),
      keyPath_(keyPath),
      message_(message),
      line_(line)
{
}

const char* toString(MotionType t)
{
    switch (t)
    {
        case MotionType::Static:
            return "static";
        case MotionType::Waypoints:
            return "waypoints";
        case MotionType::Loop:
            return "loop";
        case MotionType::RandomWalk:
            return "random_walk";
    }
    return "unknown";
}

const char* toString(CsiFormat f)
{
    switch (f)
    {
        case CsiFormat::Nexmon:
            return "nexmon";
        case CsiFormat::Intel5300:
            return "intel5300";
    }
    return "unknown";
}

ImpairmentSpec ImpairmentSpec::ideal()
{
    ImpairmentSpec s;
    s.antennaPhaseOffsets = false;
    s.antennaGainSigma_dB = 0;
    s.txChainPhaseOffsets = false;
    s.txChainGainSigma_dB = 0;
    s.cyclicShiftDelays = false;
    s.rippleAmplitude_rad = 0;
    s.samplingTimeOffsetSigma_s = 0;
    s.cfoCommonPhase = false;
    s.agcSigma_dB = 0;
    s.agcPerChainSigma_dB = 0;
    s.rssiSigma_dB = 0;
    s.awgn = false;
    s.timingJitter = 0;
    s.antennaJumps = false;
    s.firmwareOverwrittenBins = false;
    s.lowerSubbandSignFlip = false;
    return s;
}

// ------------------------------------------------------------------------- reading
namespace
{
struct Reader
{
    std::string baseDir;

    AntennaArray array(const YamlNode& n) const
    {
        if (n.isMap()) return detail::readAntennaArray(n);
        std::string path = n.asString();
        if (!path.empty() && path[0] != '/') path = baseDir + "/" + path;
        if (!mrpt::system::fileExists(path)) n.fail("antenna array file not found: " + path);
        try
        {
            return AntennaArray::fromYamlFile(path);
        }
        catch (const ScenarioError& e)
        {
            n.fail(std::string("in antenna array file: ") + e.what());
        }
    }

    static Chanspec channel(const YamlNode& n)
    {
        try
        {
            return Chanspec::fromString(n.asString());
        }
        catch (const std::invalid_argument& e)
        {
            n.fail(std::string("impossible channel: ") + e.what());
        }
    }

    static Wall wall(const YamlNode& n, const std::string& defName)
    {
        n.allowOnly({"name", "from", "to", "reflection", "transmission_loss_db"});
        Wall w;
        w.name = n.stringOr("name", defName);
        w.from = n["from"].asPoint2D();
        w.to = n["to"].asPoint2D();
        if (auto r = n.get("reflection")) w.reflection = r->asComplex();
        w.transmissionLoss_dB = n.doubleOr("transmission_loss_db", w.transmissionLoss_dB);
        return w;
    }

    void room(const YamlNode& n, Scenario& sc) const
    {
        n.allowOnly({"corners", "reflection", "transmission_loss_db"});
        const YamlNode corners = n["corners"];
        if (corners.size() < 3) corners.fail("a room needs at least 3 corners");
        for (size_t i = 0; i < corners.size(); ++i)
            sc.roomCorners.push_back(corners.at(i).asPoint2D());
        std::complex<double> refl{-0.5, 0.0};
        if (auto r = n.get("reflection")) refl = r->asComplex();
        const double loss = n.doubleOr("transmission_loss_db", 30.0);
        for (size_t i = 0; i < sc.roomCorners.size(); ++i)
        {
            Wall w;
            w.name = "room" + std::to_string(i);
            w.from = sc.roomCorners[i];
            w.to = sc.roomCorners[(i + 1) % sc.roomCorners.size()];
            w.reflection = refl;
            w.transmissionLoss_dB = loss;
            sc.walls.push_back(w);
        }
    }

    TransmitterSpec transmitter(const YamlNode& n, size_t index) const
    {
        n.allowOnly(
            {"name", "mac", "position", "yaw_deg", "channel", "streams", "array", "frame_rate_hz",
             "tx_power_dbm", "antenna_gain_dbi", "first_sequence_number"});
        TransmitterSpec t;
        t.name = n.stringOr("name", "tx" + std::to_string(index));
        const YamlNode mac = n["mac"];
        const auto parsed = MacAddress::parse(mac.asString());
        if (!parsed) mac.fail("invalid MAC address '" + mac.asString() + "'");
        t.mac = *parsed;
        const TPoint2D p = n["position"].asPoint2D();
        t.pose = {p.x, p.y, n.doubleOr("yaw_deg", 0.0) * kDeg};
        t.chanspec = channel(n["channel"]);
        t.streams = n.unsignedOr("streams", 1, 64);
        if (auto a = n.get("array")) t.array = array(*a);
        t.frameRate_Hz = n.doubleOr("frame_rate_hz", t.frameRate_Hz);
        t.txPower_dBm = n.doubleOr("tx_power_dbm", t.txPower_dBm);
        t.antennaGain_dBi = n.doubleOr("antenna_gain_dbi", t.antennaGain_dBi);
        t.firstSequenceNumber = uint16_t(n.unsignedOr("first_sequence_number", 0, 4095));
        return t;
    }

    ReceiverSpec receiver(const YamlNode& n) const
    {
        n.allowOnly(
            {"label", "array", "sensor_pose", "noise_figure_db", "antenna_gain_dbi", "chip_id",
             "body_shadow", "csi_format", "channel_schedule", "channel_dwell_s",
             "channel_switch_ms"});
        ReceiverSpec r;
        r.sensorLabel = n.stringOr("label", r.sensorLabel);
        const std::string format = n.stringOr("csi_format", toString(r.csiFormat));
        if (format == toString(CsiFormat::Intel5300))
            r.csiFormat = CsiFormat::Intel5300;
        else if (format != toString(CsiFormat::Nexmon))
            n["csi_format"].fail("unknown format '" + format + "' (nexmon or intel5300)");
        r.array = array(n["array"]);
        if (auto sp = n.get("sensor_pose"))
        {
            sp->allowOnly({"x", "y", "z", "yaw_deg"});
            r.sensorPose = mrpt::poses::CPose3D(
                sp->doubleOr("x", 0), sp->doubleOr("y", 0), sp->doubleOr("z", 0),
                sp->doubleOr("yaw_deg", 0) * kDeg, 0, 0);
        }
        r.noiseFigure_dB = n.doubleOr("noise_figure_db", r.noiseFigure_dB);
        r.antennaGain_dBi = n.doubleOr("antenna_gain_dbi", r.antennaGain_dBi);
        r.chipId = uint16_t(n.unsignedOr("chip_id", r.chipId, 0xFFFF));
        if (auto b = n.get("body_shadow"))
        {
            b->allowOnly({"center_deg", "width_deg", "attenuation_db"});
            r.bodyShadow.center_rad = b->doubleOr("center_deg", 180.0) * kDeg;
            r.bodyShadow.halfWidth_rad = 0.5 * b->doubleOr("width_deg", 90.0) * kDeg;
            r.bodyShadow.attenuation_dB = b->doubleOr("attenuation_db", 10.0);
        }
        if (auto cs = n.get("channel_schedule"))
        {
            if (!cs->isSequence() || cs->size() == 0)
                cs->fail("expected a list of channels, e.g. [42/80, 155/80, 6/20]");
            for (size_t i = 0; i < cs->size(); ++i) r.channelSchedule.push_back(channel(cs->at(i)));
        }
        r.channelDwell_s = n.doubleOr("channel_dwell_s", r.channelDwell_s);
        r.channelSwitch_s = n.doubleOr("channel_switch_ms", r.channelSwitch_s * 1e3) * 1e-3;
        return r;
    }

    static MotionSpec motion(const YamlNode& n)
    {
        n.allowOnly(
            {"type", "start", "waypoints", "speed_mps", "turn_rate_dps", "goal_tolerance_m",
             "center", "radius_m", "time_step_s", "dwell_s"});
        MotionSpec m;
        const YamlNode type = n["type"];
        const std::string t = type.asString();
        if (t == "static")
            m.type = MotionType::Static;
        else if (t == "waypoints")
            m.type = MotionType::Waypoints;
        else if (t == "loop")
            m.type = MotionType::Loop;
        else if (t == "random_walk")
            m.type = MotionType::RandomWalk;
        else
            type.fail("unknown motion type '" + t + "' (static, waypoints, loop, random_walk)");
        const YamlNode start = n["start"];
        if (!start.isSequence() || (start.size() != 2 && start.size() != 3))
            start.fail("expected [x, y] or [x, y, yaw_deg]");
        m.start = {
            start.at(0).asDouble(), start.at(1).asDouble(),
            start.size() == 3 ? start.at(2).asDouble() * kDeg : 0.0};
        if (auto w = n.get("waypoints"))
            for (size_t i = 0; i < w->size(); ++i) m.waypoints.push_back(w->at(i).asPoint2D());
        m.speed_mps = n.doubleOr("speed_mps", m.speed_mps);
        m.turnRate_radps = n.doubleOr("turn_rate_dps", m.turnRate_radps / kDeg) * kDeg;
        m.goalTolerance_m = n.doubleOr("goal_tolerance_m", m.goalTolerance_m);
        m.randomWalkCenter = {m.start.x, m.start.y};
        if (auto c = n.get("center")) m.randomWalkCenter = c->asPoint2D();
        m.randomWalkRadius_m = n.doubleOr("radius_m", m.randomWalkRadius_m);
        m.timeStep_s = n.doubleOr("time_step_s", m.timeStep_s);
        m.dwellMax_s = n.doubleOr("dwell_s", m.dwellMax_s);
        return m;
    }

    static OdometrySpec odometry(const YamlNode& n)
    {
        n.allowOnly(
            {"enabled", "label", "rate_hz", "sigma_xy_m_per_sqrt_m", "sigma_yaw_deg_per_sqrt_m",
             "sigma_yaw_per_sqrt_rad", "scale_error", "yaw_scale_error", "yaw_drift_deg_per_m",
             "start_at_origin"});
        OdometrySpec o;
        o.enabled = n.boolOr("enabled", o.enabled);
        o.sensorLabel = n.stringOr("label", o.sensorLabel);
        o.rate_Hz = n.doubleOr("rate_hz", o.rate_Hz);
        o.sigmaXY_m_per_sqrt_m = n.doubleOr("sigma_xy_m_per_sqrt_m", o.sigmaXY_m_per_sqrt_m);
        o.sigmaYaw_rad_per_sqrt_m =
            n.doubleOr("sigma_yaw_deg_per_sqrt_m", o.sigmaYaw_rad_per_sqrt_m / kDeg) * kDeg;
        o.sigmaYaw_rad_per_sqrt_rad =
            n.doubleOr("sigma_yaw_per_sqrt_rad", o.sigmaYaw_rad_per_sqrt_rad);
        o.scaleError = n.doubleOr("scale_error", o.scaleError);
        o.yawScaleError = n.doubleOr("yaw_scale_error", o.yawScaleError);
        o.yawDrift_rad_per_m =
            n.doubleOr("yaw_drift_deg_per_m", o.yawDrift_rad_per_m / kDeg) * kDeg;
        o.startAtOrigin = n.boolOr("start_at_origin", o.startAtOrigin);
        return o;
    }

    static ImpairmentSpec impairments(const YamlNode& n)
    {
        n.allowOnly(
            {"enabled",
             "antenna_phase_offsets",
             "antenna_gain_sigma_db",
             "ripple_deg",
             "ripple_components",
             "chain_delay_sigma_ns",
             "chain_delays_ns",
             "chain_phase_reference",
             "tx_chain_phase_offsets",
             "tx_chain_gain_sigma_db",
             "cyclic_shift_delays",
             "sto_sigma_ns",
             "cfo_common_phase",
             "agc_target",
             "agc_sigma_db",
             "agc_per_chain_sigma_db",
             "rssi_sigma_db",
             "awgn",
             "snr_db",
             "snr_cap_db",
             "timing_jitter",
             "retry_probability",
             "antenna_jumps",
             "dead_cores",
             "dead_cores_missing",
             "firmware_overwritten_bins",
             "lower_subband_sign_flip"});
        ImpairmentSpec s;
        if (!n.boolOr("enabled", true)) s = ImpairmentSpec::ideal();
        s.antennaPhaseOffsets = n.boolOr("antenna_phase_offsets", s.antennaPhaseOffsets);
        s.antennaGainSigma_dB = n.doubleOr("antenna_gain_sigma_db", s.antennaGainSigma_dB);
        s.rippleAmplitude_rad = n.doubleOr("ripple_deg", s.rippleAmplitude_rad / kDeg) * kDeg;
        s.rippleComponents = n.unsignedOr("ripple_components", s.rippleComponents, 16);
        s.chainDelaySigma_s = n.doubleOr("chain_delay_sigma_ns", s.chainDelaySigma_s * 1e9) * 1e-9;
        if (auto d = n.get("chain_delays_ns"))
        {
            if (d->size() < 1 || d->size() > 8) d->fail("expected a list of 1 to 8 delays [ns]");
            for (size_t i = 0; i < d->size(); ++i)
                s.chainDelays_s.push_back(d->at(i).asDouble() * 1e-9);
        }
        if (auto r = n.get("chain_phase_reference"))
        {
            try
            {
                s.chainPhaseReference = Chanspec::fromString(r->asString());
            }
            catch (const std::invalid_argument& e)
            {
                r->fail(e.what());
            }
        }
        s.txChainPhaseOffsets = n.boolOr("tx_chain_phase_offsets", s.txChainPhaseOffsets);
        s.txChainGainSigma_dB = n.doubleOr("tx_chain_gain_sigma_db", s.txChainGainSigma_dB);
        s.cyclicShiftDelays = n.boolOr("cyclic_shift_delays", s.cyclicShiftDelays);
        s.samplingTimeOffsetSigma_s =
            n.doubleOr("sto_sigma_ns", s.samplingTimeOffsetSigma_s * 1e9) * 1e-9;
        s.cfoCommonPhase = n.boolOr("cfo_common_phase", s.cfoCommonPhase);
        s.agcTarget = n.doubleOr("agc_target", s.agcTarget);
        s.agcSigma_dB = n.doubleOr("agc_sigma_db", s.agcSigma_dB);
        s.agcPerChainSigma_dB = n.doubleOr("agc_per_chain_sigma_db", s.agcPerChainSigma_dB);
        s.rssiSigma_dB = n.doubleOr("rssi_sigma_db", s.rssiSigma_dB);
        s.awgn = n.boolOr("awgn", s.awgn);
        if (auto snr = n.get("snr_db")) s.fixedSnr_dB = snr->asDouble();
        s.snrCap_dB = n.doubleOr("snr_cap_db", s.snrCap_dB);
        s.timingJitter = n.doubleOr("timing_jitter", s.timingJitter);
        s.retryProbability = n.doubleOr("retry_probability", s.retryProbability);
        if (auto j = n.get("antenna_jumps"))
        {
            j->allowOnly(
                {"enabled", "states", "step_ns", "state_delays_ns", "baseband", "rate_hz",
                 "state_phase", "allowed_states", "allowed_until_s"});
            s.antennaJumps = j->boolOr("enabled", true);
            s.jumpStates = j->unsignedOr("states", s.jumpStates, 16);
            s.jumpStep_s = j->doubleOr("step_ns", s.jumpStep_s * 1e9) * 1e-9;
            if (auto d = j->get("state_delays_ns"))
            {
                // Listed delays are the states: their count is the state count.
                if (d->size() < 1 || d->size() > 16)
                    d->fail("expected a list of 1 to 16 state delays [ns]");
                if (j->get("states") && j->unsignedOr("states", 0, 16) != d->size())
                    d->fail(
                        "lists " + std::to_string(d->size()) + " delays but 'states' is " +
                        std::to_string(j->unsignedOr("states", 0, 16)));
                for (size_t i = 0; i < d->size(); ++i)
                    s.jumpStateDelays_s.push_back(d->at(i).asDouble() * 1e-9);
                s.jumpStates = unsigned(s.jumpStateDelays_s.size());
            }
            s.jumpBaseband = j->boolOr("baseband", s.jumpBaseband);
            s.jumpRate_Hz = j->doubleOr("rate_hz", s.jumpRate_Hz);
            s.jumpStatePhase = j->boolOr("state_phase", s.jumpStatePhase);
            if (auto a = j->get("allowed_states"))
                for (size_t i = 0; i < a->size(); ++i)
                    s.jumpAllowedStates.push_back(a->at(i).asUnsigned(15));
            s.jumpAllowedUntil_s = j->doubleOr("allowed_until_s", s.jumpAllowedUntil_s);
        }
        if (auto d = n.get("dead_cores"))
            for (size_t i = 0; i < d->size(); ++i) s.deadCores.push_back(d->at(i).asUnsigned(7));
        s.deadCoresMissing = n.boolOr("dead_cores_missing", s.deadCoresMissing);
        s.firmwareOverwrittenBins =
            n.boolOr("firmware_overwritten_bins", s.firmwareOverwrittenBins);
        s.lowerSubbandSignFlip = n.boolOr("lower_subband_sign_flip", s.lowerSubbandSignFlip);
        return s;
    }

    Scenario scenario(const YamlNode& r) const
    {
        r.allowOnly(
            {"name", "description", "duration_s", "seed", "start_time_unix", "room", "walls",
             "obstacles", "scatterers", "transmitters", "receiver", "motion", "odometry",
             "impairments", "propagation"});
        Scenario sc;
        sc.name = r.stringOr("name", "unnamed");
        sc.description = r.stringOr("description", "");
        sc.duration_s = r.doubleOr("duration_s", sc.duration_s);
        sc.seed = r.unsignedOr("seed", sc.seed);
        sc.startTime_unix = r.doubleOr("start_time_unix", sc.startTime_unix);
        if (auto room = r.get("room")) this->room(*room, sc);
        if (auto walls = r.get("walls"))
            for (size_t i = 0; i < walls->size(); ++i)
                sc.walls.push_back(wall(walls->at(i), "wall" + std::to_string(i)));
        if (auto obs = r.get("obstacles"))
            for (size_t i = 0; i < obs->size(); ++i)
            {
                const YamlNode o = obs->at(i);
                o.allowOnly({"name", "from", "to", "attenuation_db"});
                Obstacle ob;
                ob.name = o.stringOr("name", "obstacle" + std::to_string(i));
                ob.from = o["from"].asPoint2D();
                ob.to = o["to"].asPoint2D();
                ob.attenuation_dB = o.doubleOr("attenuation_db", ob.attenuation_dB);
                sc.obstacles.push_back(ob);
            }
        if (auto scs = r.get("scatterers"))
            for (size_t i = 0; i < scs->size(); ++i)
            {
                const YamlNode s = scs->at(i);
                s.allowOnly({"name", "position", "rcs_m2", "phase_deg"});
                Scatterer sct;
                sct.name = s.stringOr("name", "scatterer" + std::to_string(i));
                sct.position = s["position"].asPoint2D();
                sct.radarCrossSection_m2 = s.doubleOr("rcs_m2", sct.radarCrossSection_m2);
                sct.phase_rad = s.doubleOr("phase_deg", 0.0) * kDeg;
                sc.scatterers.push_back(sct);
            }
        const YamlNode txs = r["transmitters"];
        for (size_t i = 0; i < txs.size(); ++i)
            sc.transmitters.push_back(transmitter(txs.at(i), i));
        sc.receiver = receiver(r["receiver"]);
        if (auto m = r.get("motion")) sc.motion = motion(*m);
        if (auto o = r.get("odometry")) sc.odometry = odometry(*o);
        if (auto imp = r.get("impairments")) sc.impairments = impairments(*imp);
        // The chains' offsets are those drawn for the first transmitter's channel there (as
        // before delays were modelled) and follow the delays elsewhere.
        if (!sc.impairments.chainPhaseReference && !sc.transmitters.empty())
            sc.impairments.chainPhaseReference = sc.transmitters.front().chanspec;
        if (auto p = r.get("propagation"))
        {
            p->allowOnly({"max_reflection_order", "min_path_gain_db"});
            sc.propagation.maxReflectionOrder = p->unsignedOr("max_reflection_order", 2, 2);
            sc.propagation.minPathGain_dB = p->doubleOr("min_path_gain_db", -40.0);
        }
        return sc;
    }
};
}  // namespace

Scenario Scenario::fromYamlText(
    const std::string& text, const std::string& displayName, const std::string& baseDir)
{
    auto doc = detail::YamlDocument::parse(text, displayName);
    const YamlNode root = YamlNode::root(doc);
    if (!root.isMap())
        root.fail("a scenario file is a map of keys (see share/scenarios/README.md)");
    Reader reader{baseDir};
    Scenario sc = reader.scenario(root);
    try
    {
        sc.validate();
    }
    catch (const ScenarioError& e)
    {
        throw ScenarioError(displayName, doc->lineOf(e.keyPath()), e.keyPath(), e.message());
    }
    return sc;
}

Scenario Scenario::fromYamlFile(const std::string& path)
{
    std::ifstream f(path);
    if (!f) throw ScenarioError(path, 0, "", "cannot open scenario file");
    std::stringstream ss;
    ss << f.rdbuf();
    std::string dir = mrpt::system::extractFileDirectory(path);
    if (dir.empty()) dir = ".";
    Scenario sc = fromYamlText(ss.str(), path, dir);
    sc.sourcePath = path;
    if (sc.name == "unnamed") sc.name = mrpt::system::extractFileName(path);
    return sc;
}

// ------------------------------------------------------------------------- checks
double ReceiverSpec::BodyShadow::loss_dB(double aoa_rad) const
{
    if (attenuation_dB <= 0) return 0;
    constexpr double kEdge = 10 * M_PI / 180;
    const double off = std::abs(mrpt::math::wrapToPi(aoa_rad - center_rad));
    if (off <= halfWidth_rad) return attenuation_dB;
    if (off >= halfWidth_rad + kEdge) return 0;
    return attenuation_dB * 0.5 * (1 + std::cos(M_PI * (off - halfWidth_rad) / kEdge));
}

double ReceiverSpec::nextListeningTime(const Chanspec& cs, double t_s) const
{
    if (channelSchedule.empty()) return t_s;
    const auto it = std::find_if(
        channelSchedule.begin(), channelSchedule.end(),
        [&](const Chanspec& c) { return c.sameChannel(cs); });
    if (it == channelSchedule.end()) return std::numeric_limits<double>::infinity();
    if (channelSchedule.size() == 1) return t_s;
    // Slot k: listening on channel k during [k·L, k·L + dwell), then switching; L = dwell+switch.
    const double slot = channelDwell_s + channelSwitch_s;
    const double cycle = slot * double(channelSchedule.size());
    const double opens = slot * double(it - channelSchedule.begin());
    const double cycleStart = std::floor(t_s / cycle) * cycle;
    const double within = t_s - cycleStart;
    if (within < opens) return cycleStart + opens;
    if (within < opens + channelDwell_s) return t_s;
    return cycleStart + cycle + opens;
}

bool Scenario::insideRoom(const TPoint2D& p) const
{
    if (roomCorners.size() < 3) return true;
    return mrpt::math::TPolygon2D(roomCorners).contains(p);
}

size_t Scenario::transmitterIndex(const std::string& nameOrMac) const
{
    const auto mac = MacAddress::parse(nameOrMac);
    for (size_t i = 0; i < transmitters.size(); ++i)
        if (transmitters[i].name == nameOrMac || (mac && transmitters[i].mac == *mac)) return i;
    throw std::out_of_range("no transmitter named '" + nameOrMac + "'");
}

void Scenario::validate() const
{
    auto fail = [](const std::string& key, const std::string& msg)
    { throw ScenarioError("", 0, key, msg); };
    auto where = [](const TPoint2D& p)
    {
        std::ostringstream s;
        s << "[" << p.x << ", " << p.y << "]";
        return s.str();
    };

    if (!(duration_s > 0)) fail("duration_s", "must be > 0");
    double twiceArea = 0;  // shoelace
    for (size_t i = 0; i < roomCorners.size(); ++i)
    {
        const auto& a = roomCorners[i];
        const auto& b = roomCorners[(i + 1) % roomCorners.size()];
        twiceArea += a.x * b.y - b.x * a.y;
    }
    if (roomCorners.size() >= 3 && std::abs(twiceArea) < 1e-6)
        fail("room.corners", "the room has no area");
    const size_t roomWalls = roomCorners.size() >= 3 ? roomCorners.size() : 0;
    for (size_t i = 0; i < walls.size(); ++i)
    {
        const std::string key =
            i < roomWalls ? "room.corners" : "walls[" + std::to_string(i - roomWalls) + "]";
        if (std::hypot(walls[i].to.x - walls[i].from.x, walls[i].to.y - walls[i].from.y) < 1e-6)
            fail(key, "wall '" + walls[i].name + "' has zero length");
        if (std::abs(walls[i].reflection) > 1.0)
            fail(key + ".reflection", "|reflection coefficient| must be <= 1");
    }
    for (size_t i = 0; i < scatterers.size(); ++i)
    {
        const std::string key = "scatterers[" + std::to_string(i) + "]";
        if (!insideRoom(scatterers[i].position))
            fail(key + ".position", where(scatterers[i].position) + " is outside the room");
        if (!(scatterers[i].radarCrossSection_m2 >= 0)) fail(key + ".rcs_m2", "must be >= 0");
    }

    if (transmitters.empty()) fail("transmitters", "at least one transmitter is needed");
    std::set<std::string> names;
    std::set<MacAddress> macs;
    for (size_t i = 0; i < transmitters.size(); ++i)
    {
        const auto& t = transmitters[i];
        const std::string key = "transmitters[" + std::to_string(i) + "]";
        if (!names.insert(t.name).second) fail(key + ".name", "duplicate name '" + t.name + "'");
        if (t.name.empty() || t.name.find_first_of(",\"\n\r\t ") != std::string::npos)
            fail(key + ".name", "a name needs no spaces, commas or quotes: '" + t.name + "'");
        if (!macs.insert(t.mac).second) fail(key + ".mac", "duplicate MAC " + t.mac.asString());
        if (!insideRoom({t.pose.x, t.pose.y}))
            fail(
                key + ".position", "transmitter '" + t.name + "' at " +
                                       where({t.pose.x, t.pose.y}) + " is outside the room");
        if (t.streams < 1 || t.streams > CObservationWiFiCSI::kMaxChains)
            fail(key + ".streams", "must be 1.." + std::to_string(CObservationWiFiCSI::kMaxChains));
        if (t.array.size() < t.streams)
            fail(
                key + ".array", std::to_string(t.streams) +
                                    " streams need an array with at least " +
                                    std::to_string(t.streams) + " elements (has " +
                                    std::to_string(t.array.size()) + ")");
        if (!(t.frameRate_Hz > 0 && t.frameRate_Hz <= 10000))
            fail(key + ".frame_rate_hz", "must be in (0, 10000]");
    }

    const size_t nRx = receiver.array.size();
    if (nRx < 1 || nRx > CObservationWiFiCSI::kMaxChains)
        fail(
            "receiver.array", "the receiver needs 1.." +
                                  std::to_string(CObservationWiFiCSI::kMaxChains) + " elements");
    if (receiver.csiFormat == CsiFormat::Intel5300)
    {
        if (nRx > 3)
            fail("receiver.array", "csi_format intel5300: the 5300 has at most 3 antennas");
        for (size_t i = 0; i < transmitters.size(); ++i)
        {
            const auto& t = transmitters[i];
            if (t.chanspec.bandwidthMHz > 40)
                fail(
                    "transmitters[" + std::to_string(i) + "].channel",
                    "csi_format intel5300 reports 20 or 40 MHz only, not " + t.chanspec.asString());
            if (t.streams > 3)
                fail(
                    "transmitters[" + std::to_string(i) + "].streams",
                    "csi_format intel5300: at most 3 streams");
        }
    }

    const auto& schedule = receiver.channelSchedule;
    std::vector<Chanspec> used;  // the transmitters' channels, each once
    if (!schedule.empty())
        for (const auto& t : transmitters)
            if (std::none_of(
                    used.begin(), used.end(),
                    [&](const Chanspec& c) { return c.sameChannel(t.chanspec); }))
                used.push_back(t.chanspec);
    for (size_t i = 0; i < schedule.size(); ++i)
    {
        const std::string key = "receiver.channel_schedule[" + std::to_string(i) + "]";
        for (size_t j = 0; j < i; ++j)
            if (schedule[j].sameChannel(schedule[i]))
                fail(
                    key, schedule[i].asString() + " is already in the schedule (entry " +
                             std::to_string(j) + ")");
        // A channel no transmitter uses only costs listening time: most likely a typo.
        if (std::none_of(
                used.begin(), used.end(),
                [&](const Chanspec& c) { return c.sameChannel(schedule[i]); }))
        {
            std::string list;
            for (const auto& c : used) list += (list.empty() ? "" : ", ") + c.asString();
            fail(
                key, "no transmitter is on " + schedule[i].asString() + " (they use " + list + ")");
        }
    }
    if (!schedule.empty())
    {
        if (!(receiver.channelDwell_s > 0 && receiver.channelDwell_s < 1e6))
            fail("receiver.channel_dwell_s", "must be > 0 s");
        if (!(receiver.channelSwitch_s >= 0 && receiver.channelSwitch_s < 1e3))
            fail("receiver.channel_switch_ms", "must be >= 0 ms");
    }

    const auto& m = motion;
    if (!insideRoom({m.start.x, m.start.y}))
        fail("motion.start", "start " + where({m.start.x, m.start.y}) + " is outside the room");
    if (!(m.speed_mps > 0 && m.speed_mps < 20)) fail("motion.speed_mps", "must be in (0, 20)");
    if (!(m.turnRate_radps > 0)) fail("motion.turn_rate_dps", "must be > 0");
    if (!(m.timeStep_s > 0 && m.timeStep_s <= 0.1))
        fail("motion.time_step_s", "must be in (0, 0.1]");
    if (!(m.goalTolerance_m > 0)) fail("motion.goal_tolerance_m", "must be > 0");
    if (!(m.dwellMax_s >= 0)) fail("motion.dwell_s", "must be >= 0");
    const auto& body = receiver.bodyShadow;
    if (!(body.attenuation_dB >= 0 && body.attenuation_dB <= 60))
        fail("receiver.body_shadow.attenuation_db", "must be in [0, 60]");
    if (!(body.halfWidth_rad >= 0 && body.halfWidth_rad <= M_PI))
        fail("receiver.body_shadow.width_deg", "must be in [0, 360]");
    if (m.type == MotionType::Waypoints || m.type == MotionType::Loop)
    {
        if (m.waypoints.size() < (m.type == MotionType::Loop ? 2u : 1u))
            fail(
                "motion.waypoints",
                std::string("too few waypoints for '") + toString(m.type) + "'");
        for (size_t i = 0; i < m.waypoints.size(); ++i)
            if (!insideRoom(m.waypoints[i]))
                fail(
                    "motion.waypoints[" + std::to_string(i) + "]",
                    "waypoint " + where(m.waypoints[i]) + " is outside the room");
        // The robot drives straight between waypoints: through walls it can't.
        auto crosses =
            [](const TPoint2D& p, const TPoint2D& q, const TPoint2D& a, const TPoint2D& b)
        {
            auto side = [](const TPoint2D& o, const TPoint2D& u, const TPoint2D& v)
            { return (u.x - o.x) * (v.y - o.y) - (u.y - o.y) * (v.x - o.x); };
            return (side(a, b, p) > 0) != (side(a, b, q) > 0) &&
                   (side(p, q, a) > 0) != (side(p, q, b) > 0);
        };
        const size_t legs = m.waypoints.size() + (m.type == MotionType::Loop ? 1 : 0);
        for (size_t i = 0; i < legs; ++i)
        {
            const TPoint2D from = i == 0 ? TPoint2D(m.start.x, m.start.y) : m.waypoints[i - 1];
            const TPoint2D to = m.waypoints[i % m.waypoints.size()];
            const std::string key =
                "motion.waypoints[" + std::to_string(i % m.waypoints.size()) + "]";
            for (const auto& w : walls)
                if (crosses(from, to, w.from, w.to))
                    fail(
                        key, "the drive " + where(from) + " -> " + where(to) + " crosses wall '" +
                                 w.name + "'");
            for (const auto& o : obstacles)
                if (crosses(from, to, o.from, o.to))
                    fail(
                        key, "the drive " + where(from) + " -> " + where(to) +
                                 " crosses obstacle '" + o.name + "'");
        }
    }
    if (m.type == MotionType::RandomWalk)
    {
        if (!(m.randomWalkRadius_m > 0)) fail("motion.radius_m", "must be > 0");
        if (!insideRoom(m.randomWalkCenter))
            fail("motion.center", "centre " + where(m.randomWalkCenter) + " is outside the room");
    }

    if (odometry.enabled && !(odometry.rate_Hz > 0 && odometry.rate_Hz <= 1000))
        fail("odometry.rate_hz", "must be in (0, 1000]");

    const auto& imp = impairments;
    for (size_t i = 0; i < imp.deadCores.size(); ++i)
        if (imp.deadCores[i] >= nRx)
            fail(
                "impairments.dead_cores[" + std::to_string(i) + "]",
                "core " + std::to_string(imp.deadCores[i]) + " does not exist (receiver has " +
                    std::to_string(nRx) + ")");
    if (!(imp.timingJitter >= 0 && imp.timingJitter < 1))
        fail("impairments.timing_jitter", "must be in [0, 1)");
    if (!(imp.retryProbability >= 0 && imp.retryProbability < 1))
        fail("impairments.retry_probability", "must be in [0, 1)");
    if (imp.antennaJumps && imp.jumpStates < 1)
        fail("impairments.antenna_jumps.states", "must be >= 1");
    if (!imp.jumpStateDelays_s.empty() && imp.jumpStateDelays_s.size() != imp.jumpStates)
        fail(
            "impairments.antenna_jumps.state_delays_ns",
            "lists " + std::to_string(imp.jumpStateDelays_s.size()) + " delays for " +
                std::to_string(imp.jumpStates) + " states");
    for (size_t i = 0; i < imp.jumpStateDelays_s.size(); ++i)
        if (!(std::abs(imp.jumpStateDelays_s[i]) <= 1e-6))
            fail(
                "impairments.antenna_jumps.state_delays_ns[" + std::to_string(i) + "]",
                "must be a number within ±1000 ns");
    for (size_t i = 0; i < imp.jumpAllowedStates.size(); ++i)
        if (imp.jumpAllowedStates[i] >= imp.jumpStates)
            fail(
                "impairments.antenna_jumps.allowed_states[" + std::to_string(i) + "]",
                "state " + std::to_string(imp.jumpAllowedStates[i]) +
                    " does not exist (states: " + std::to_string(imp.jumpStates) + ")");
    if (!(imp.jumpAllowedUntil_s > 0))
        fail("impairments.antenna_jumps.allowed_until_s", "must be > 0");
    if (!(imp.agcTarget > 0)) fail("impairments.agc_target", "must be > 0");
    if (propagation.maxReflectionOrder > 2)
        fail("propagation.max_reflection_order", "must be 0, 1 or 2");
}

}  // namespace mrpt_wifi::sim
