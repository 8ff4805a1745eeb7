/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/localization/SyntheticBearings.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::localization
{
namespace
{
std::vector<std::string> split(const std::string& line)
{
    std::vector<std::string> out;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) out.push_back(c);
    return out;
}

// Reports an angle as an estimator on a linear array does: the candidate in the front
// half-plane first, its mirror second.
void reportWithMirror(
    const ArrayGeometry& g, double noisy, double& primary, bool& ambiguous, double& mirror)
{
    if (!g.linear || g.elements.size() < 2)
    {
        primary = wrapToPi(noisy), ambiguous = false, mirror = primary;
        return;
    }
    const double m = g.mirrorOf(noisy);
    ambiguous = true;
    if (g.inFrontHalf(noisy))
        primary = wrapToPi(noisy), mirror = m;
    else
        primary = m, mirror = wrapToPi(noisy);
}
}  // namespace

std::vector<BearingRecord> synthesizeBearings(
    const std::string& path, const TransmitterMap& txs, const SyntheticBearingOptions& opt,
    SyntheticBearingStats* statsOut)
{
    std::ifstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot open frames.csv");
    std::string line;
    if (!std::getline(f, line)) throw std::runtime_error(path + ": empty file");
    std::map<std::string, size_t> col;
    {
        const auto h = split(line);
        for (size_t i = 0; i < h.size(); ++i) col[h[i]] = i;
    }
    for (const char* k :
         {"timestamp_unix", "mac", "robot_x", "robot_y", "robot_yaw_rad", "sensor_x", "sensor_y",
          "sensor_yaw_rad", "aoa_rad", "aod_rad", "strongest_aoa_rad"})
        if (!col.count(k)) throw std::runtime_error(path + ": missing column '" + k + "'");

    mrpt::random::CRandomGenerator rng(opt.seed);
    SyntheticBearingStats st;
    std::map<MacAddress, double> lastKept;
    std::vector<BearingRecord> out;
    int lineNo = 1;
    while (std::getline(f, line))
    {
        ++lineNo;
        if (line.empty()) continue;
        const auto c = split(line);
        if (c.size() < col.size())
            throw std::runtime_error(path + ":" + std::to_string(lineNo) + ": short row");
        auto num = [&](const char* k) { return std::stod(c[col[k]]); };
        st.frames++;
        BearingRecord r;
        r.t = num("timestamp_unix");
        const auto mac = MacAddress::parse(c[col["mac"]]);
        if (!mac) throw std::runtime_error(path + ":" + std::to_string(lineNo) + ": bad MAC");
        r.transmitter = *mac;
        const KnownTransmitter* tx = txs.find(*mac);
        if (!tx)
        {
            st.unknownTransmitter++;
            continue;
        }
        if (opt.rate_Hz > 0)
        {
            auto it = lastKept.find(*mac);
            if (it != lastKept.end() && r.t - it->second < 1.0 / opt.rate_Hz - 1e-6) continue;
            lastKept[*mac] = r.t;
        }
        // Receive array pose on the robot from the two world poses in the row.
        const mrpt::math::TPose2D robot(num("robot_x"), num("robot_y"), num("robot_yaw_rad"));
        const double dx = num("sensor_x") - robot.x, dy = num("sensor_y") - robot.y;
        const double cr = std::cos(robot.phi), sr = std::sin(robot.phi);
        r.sensorPose = mrpt::math::TPose2D(
            cr * dx + sr * dy, -sr * dx + cr * dy, wrapToPi(num("sensor_yaw_rad") - robot.phi));

        double aoa = num("aoa_rad");
        if (opt.strongestPathErrors && std::abs(wrapToPi(num("strongest_aoa_rad") - aoa)) > 1e-6)
            aoa = num("strongest_aoa_rad"), st.strongestPath++;
        if (rng.drawUniform(0.0, 1.0) < opt.outlierFraction)
            aoa = rng.drawUniform(-M_PI, M_PI), st.outliers++;
        else
            aoa += opt.aoaStd_rad * rng.drawGaussian1D_normalized();
        r.hasAoa = true;
        r.aoaStd = opt.aoaStd_rad;
        reportWithMirror(opt.rxArray, aoa, r.aoa, r.aoaAmbiguous, r.aoaMirror);

        if (opt.aod && tx->array.elements.size() >= 2)
        {
            double aod = num("aod_rad");
            if (rng.drawUniform(0.0, 1.0) < opt.outlierFraction)
                aod = rng.drawUniform(-M_PI, M_PI), st.outliers++;
            else
                aod += opt.aodStd_rad * rng.drawGaussian1D_normalized();
            r.hasAod = true;
            r.aodStd = opt.aodStd_rad;
            reportWithMirror(tx->array, aod, r.aod, r.aodAmbiguous, r.aodMirror);
        }
        out.push_back(r);
        st.kept++;
    }
    if (statsOut) *statsOut = st;
    return out;
}

}  // namespace mrpt_wifi::localization
