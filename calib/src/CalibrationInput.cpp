/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/containers/yaml.h>
#include <mrpt/core/exceptions.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/calib/CalibrationInput.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/obs/RawlogReader.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::calib
{
namespace
{
/** First line of an exception's message (MRPT banner and backtrace removed). */
std::string firstLine(const std::exception& e)
{
    const std::string msg = cli::exceptionMessage(e);
    return msg.substr(0, msg.find('\n'));
}
}  // namespace

std::vector<TransmitterSite> loadTransmitterSites(const std::string& path)
{
    std::ifstream f(path);
    if (!f) throw std::runtime_error("cannot open transmitters file '" + path + "'");
    std::stringstream ss;
    ss << f.rdbuf();
    mrpt::containers::yaml doc;
    try
    {
        doc = mrpt::containers::yaml::FromText(ss.str());
    }
    catch (const std::exception& e)
    {
        throw std::runtime_error(path + ": YAML syntax error: " + firstLine(e));
    }
    if (!doc.isMap() || !doc.has("transmitters") || !doc["transmitters"].isSequence())
        throw std::runtime_error(path + ": expected a list under the key 'transmitters'");

    std::vector<TransmitterSite> sites;
    const auto& seq = doc["transmitters"].asSequence();
    for (size_t i = 0; i < seq.size(); ++i)
    {
        const std::string where = path + ": transmitters[" + std::to_string(i) + "]";
        const mrpt::containers::yaml e(seq[i]);
        if (!e.isMap()) throw std::runtime_error(where + ": expected a map");
        TransmitterSite s;
        s.name = e.has("name") ? e["name"].as<std::string>() : "tx" + std::to_string(i);
        if (e.has("mac"))
        {
            const auto mac = MacAddress::parse(e["mac"].as<std::string>());
            if (!mac)
                throw std::runtime_error(
                    where + ".mac: '" + e["mac"].as<std::string>() + "' is not a MAC address");
            s.mac = *mac;
        }
        if (!e.has("position") || !e["position"].isSequence() ||
            e["position"].asSequence().size() != 2)
            throw std::runtime_error(where + ".position: expected [x, y] in metres");
        try
        {
            s.position.x = e["position"].asSequence()[0].as<double>();
            s.position.y = e["position"].asSequence()[1].as<double>();
        }
        catch (const std::exception&)
        {
            throw std::runtime_error(where + ".position: expected two numbers");
        }
        try
        {
            if (e.has("yaw_deg")) s.yaw_rad = e["yaw_deg"].as<double>() * M_PI / 180;
        }
        catch (const std::exception&)
        {
            throw std::runtime_error(where + ".yaw_deg: expected a number (degrees)");
        }
        if (e.has("array"))
        {
            // Beside this file, else a shipped array by name (`ap-linear-4`).
            try
            {
                s.array = AntennaArray::fromFileOrName(
                    e["array"].as<std::string>(), where + ".array",
                    mrpt::system::extractFileDirectory(path));
            }
            catch (const std::exception& ex)
            {
                throw std::runtime_error(where + ".array: " + firstLine(ex));
            }
        }
        else if (e.has("array_elements"))
        {
            const auto& el = e["array_elements"];
            if (!el.isSequence())
                throw std::runtime_error(where + ".array_elements: expected a list");
            AntennaArray a;
            a.name = s.name + "-array";
            for (const auto& p : el.asSequence())
            {
                const mrpt::containers::yaml xy(p);
                if (!xy.isSequence() || xy.asSequence().size() != 2)
                    throw std::runtime_error(where + ".array_elements: expected [[x, y], ...]");
                a.elements.push_back(
                    {xy.asSequence()[0].as<double>(), xy.asSequence()[1].as<double>()});
            }
            s.array = a;
        }
        sites.push_back(s);
    }
    if (sites.empty()) throw std::runtime_error(path + ": the transmitter list is empty");
    return sites;
}

void readRawlog(
    const std::string& path, const std::function<void(const CObservationWiFiCSI&)>& onCsi,
    const std::function<void(double, const mrpt::math::TPose2D&)>& onOdometry,
    const std::function<void(double)>& onProgress)
{
    if (!mrpt::system::fileExists(path))
        throw std::runtime_error("rawlog '" + path + "': cannot open: no such file");
    forEachRawlogObservation(
        path,
        [&](const mrpt::obs::CObservation::Ptr& o)
        {
            if (auto csi = std::dynamic_pointer_cast<CObservationWiFiCSI>(o))
            {
                if (onCsi) onCsi(*csi);
            }
            else if (auto odo = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(o))
            {
                if (onOdometry)
                    onOdometry(mrpt::Clock::toDouble(odo->timestamp), odo->odometry.asTPose());
            }
        },
        onProgress);
}

RawlogSummary summarizeRawlog(
    const std::string& path, const std::function<void(double)>& onProgress)
{
    RawlogSummary s;
    readRawlog(
        path,
        [&](const CObservationWiFiCSI& obs)
        {
            const double t = mrpt::Clock::toDouble(obs.timestamp);
            if (s.csiFrames == 0) s.firstCsiTime = t;
            s.lastCsiTime = t;
            ++s.csiFrames;
            auto& src = s.transmitters[obs.transmitter];
            ++src.frames;
            ++src.channels[obs.chanspec.asString()];
            if (obs.nRx > src.maxRx) src.rxCores = obs.rxCores;
            src.maxRx = std::max<unsigned>(src.maxRx, obs.nRx);
            src.minRssi = std::min<int>(src.minRssi, obs.rssi_dBm);
            src.maxRssi = std::max<int>(src.maxRssi, obs.rssi_dBm);
        },
        [&](double t, const mrpt::math::TPose2D& p)
        {
            ++s.odometryReadings;
            s.odometry.add(t, p);
        },
        onProgress);
    return s;
}

}  // namespace mrpt_wifi::calib
