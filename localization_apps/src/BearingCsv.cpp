/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/core/bits_math.h>
#include <mrpt_wifi/localization/BearingRecord.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace mrpt_wifi::localization
{
namespace
{
std::vector<std::string> splitCsv(const std::string& line)
{
    std::vector<std::string> out;
    std::string cur;
    for (char c : line)
    {
        if (c == ',')
            out.push_back(cur), cur.clear();
        else if (c != '\r')
            cur += c;
    }
    out.push_back(cur);
    for (auto& s : out)
    {
        const auto b = s.find_first_not_of(" \t\"'");
        const auto e = s.find_last_not_of(" \t\"'");
        s = b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
    }
    return out;
}
}  // namespace

std::string InputWarnings::summary() const
{
    std::ostringstream o;
    o << unknownTransmitter << " bearings of unknown transmitters, " << outsideTrajectory
      << " outside the trajectory's time span, " << noAngle << " rows without an angle";
    if (flaggedOffAngles) o << ", " << flaggedOffAngles << " angle cells flagged not measured";
    return o.str();
}

std::string InputWarnings::csvWarning(const std::string& path) const
{
    if (!flaggedOffAngles) return {};
    return "warning: " + path + ": " + std::to_string(flaggedOffAngles) +
           " rows carry an angle in aoa_deg/aod_deg while their has_aoa/has_aod flag is 0; those "
           "angles were not measured and are ignored (older csi-bearings --csv wrote 0.000 "
           "there)\n";
}

std::vector<BearingRecord> readBearingCsv(
    const std::string& path, const BearingCsvOptions& opt, InputWarnings* warnings)
{
    std::ifstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot open bearings CSV");
    std::string line;
    int lineNo = 0;
    std::map<std::string, int> col;
    std::vector<BearingRecord> out;
    auto fail = [&](const std::string& msg)
    { throw std::runtime_error(path + ":" + std::to_string(lineNo) + ": " + msg); };

    while (std::getline(f, line))
    {
        ++lineNo;
        if (line.empty() || line[0] == '#' || line.find_first_not_of(" \t\r") == std::string::npos)
            continue;
        const auto cells = splitCsv(line);
        if (col.empty())
        {
            for (size_t i = 0; i < cells.size(); ++i) col[cells[i]] = int(i);
            if (!col.count("timestamp") || !col.count("transmitter"))
                fail("header must name 'timestamp' and 'transmitter' columns");
            if (!col.count("aoa_deg") && !col.count("aod_deg"))
                fail("header must name an 'aoa_deg' or 'aod_deg' column");
            continue;
        }
        auto cell = [&](const char* name) -> std::string
        {
            const auto it = col.find(name);
            if (it == col.end() || size_t(it->second) >= cells.size()) return {};
            return cells[size_t(it->second)];
        };
        auto num = [&](const char* name, double& v) -> bool
        {
            const std::string s = cell(name);
            if (s.empty() || s == "nan" || s == "NaN") return false;
            try
            {
                size_t used = 0;
                v = std::stod(s, &used);
                if (used != s.size() || !std::isfinite(v)) throw std::invalid_argument(s);
            }
            catch (const std::exception&)
            {
                fail(std::string("column '") + name + "': not a number: '" + s + "'");
            }
            return true;
        };

        BearingRecord r;
        if (!num("timestamp", r.t)) fail("empty timestamp");
        const std::string tx = cell("transmitter");
        if (const auto mac = MacAddress::parse(tx))
            r.transmitter = *mac;
        else if (const KnownTransmitter* k = opt.names ? opt.names->findByText(tx) : nullptr)
            r.transmitter = k->mac;
        else
            fail("transmitter '" + tx + "' is neither a MAC nor a name in the map");
        r.sensorPose = opt.sensorPose;

        // Optional 0/1 flag columns (csi-bearings --csv writes them, with zeros in the cells of
        // what it did not measure): a 0 flag overrides the angle cells.
        auto flag = [&](const char* name)
        {
            const std::string c = cell(name);
            return !(c == "0" || c == "false");
        };
        double v = 0;
        // A 0 flag next to a filled angle cell: older csi-bearings wrote 0.000 there. Not used,
        // but counted so the apps can warn (the cell might be a real angle the flag disowns).
        for (const auto& [flagCol, angleCol] :
             {std::pair{"has_aoa", "aoa_deg"}, {"has_aod", "aod_deg"}})
            if (!flag(flagCol) && !cell(angleCol).empty() && warnings) warnings->flaggedOffAngles++;
        if (flag("has_aoa") && num("aoa_deg", v))
        {
            r.hasAoa = true;
            r.aoa = wrapToPi(mrpt::DEG2RAD(v));
            r.aoaStd = num("aoa_std_deg", v) ? mrpt::DEG2RAD(v) : opt.defaultStd_rad;
            if (flag("aoa_ambiguous") && num("aoa_mirror_deg", v))
                r.aoaAmbiguous = true, r.aoaMirror = wrapToPi(mrpt::DEG2RAD(v));
            double weight = 0, directionStd = 0;
            if (num("aoa_alt_deg", v) && num("aoa_alt_weight", weight) &&
                num("aoa_direction_std_deg", directionStd))
            {
                if (!(weight > 0 && weight <= 1) || !(directionStd > 0))
                    fail("aoa_alt_weight must be in (0, 1] and aoa_direction_std_deg > 0");
                r.hasAoaAlternative = true;
                r.aoaAlternative = wrapToPi(mrpt::DEG2RAD(v));
                r.aoaAlternativeWeight = weight;
                r.aoaDirectionStd = mrpt::DEG2RAD(directionStd);
                // "deg:weight;deg:weight": the second and later alternatives.
                std::istringstream more(cell("aoa_more_alts"));
                std::string item;
                while (std::getline(more, item, ';'))
                {
                    if (item.empty()) continue;
                    const auto colon = item.find(':');
                    double a = 0, w = 0;
                    char* end = nullptr;
                    bool ok = colon != std::string::npos;
                    if (ok) a = std::strtod(item.c_str(), &end), ok = end == item.c_str() + colon;
                    if (ok)
                        w = std::strtod(item.c_str() + colon + 1, &end),
                        ok = *end == 0 && std::isfinite(a) && w > 0 && w <= 1;
                    if (!ok)
                        fail(
                            "aoa_more_alts: '" + item +
                            "' is not DEG:WEIGHT with a weight in (0, 1]");
                    r.moreAoaAlternatives.push_back({wrapToPi(mrpt::DEG2RAD(a)), w});
                }
            }
            else if (!cell("aoa_more_alts").empty())
                fail(
                    "aoa_more_alts without a first alternative (aoa_alt_deg, aoa_alt_weight, "
                    "aoa_direction_std_deg)");
        }
        if (flag("has_aod") && num("aod_deg", v))
        {
            r.hasAod = true;
            r.aod = wrapToPi(mrpt::DEG2RAD(v));
            r.aodStd = num("aod_std_deg", v) ? mrpt::DEG2RAD(v) : opt.defaultStd_rad;
            if (flag("aod_ambiguous") && num("aod_mirror_deg", v))
                r.aodAmbiguous = true, r.aodMirror = wrapToPi(mrpt::DEG2RAD(v));
        }
        if ((r.hasAoa && r.aoaStd <= 0) || (r.hasAod && r.aodStd <= 0))
            fail("standard deviations must be > 0");
        if (!r.hasAoa && !r.hasAod)
        {
            if (warnings) warnings->noAngle++;
            continue;
        }
        out.push_back(r);
    }
    if (col.empty()) throw std::runtime_error(path + ": empty bearings CSV (no header)");
    return out;
}

void writeBearingCsv(const std::string& path, const std::vector<BearingRecord>& records)
{
    std::ofstream f(path);
    if (!f) throw std::runtime_error(path + ": cannot write");
    f << "# mrpt_wifi bearings CSV: angles in degrees, AoA in the robot's receive-array frame, "
         "AoD in the transmitter's array frame\n";
    f << "timestamp,transmitter,aoa_deg,aoa_std_deg,aoa_mirror_deg,aod_deg,aod_std_deg,"
         "aod_mirror_deg,aoa_alt_deg,aoa_alt_weight,aoa_direction_std_deg,aoa_more_alts\n";
    char buf[256];
    for (const auto& r : records)
    {
        auto ang = [&](bool has, double v) -> std::string
        {
            if (!has) return "";
            std::snprintf(buf, sizeof(buf), "%.3f", mrpt::RAD2DEG(v));
            return buf;
        };
        std::snprintf(buf, sizeof(buf), "%.6f", r.t);
        f << buf << ',' << r.transmitter.asString() << ',' << ang(r.hasAoa, r.aoa) << ','
          << ang(r.hasAoa, r.aoaStd) << ',' << ang(r.hasAoa && r.aoaAmbiguous, r.aoaMirror) << ','
          << ang(r.hasAod, r.aod) << ',' << ang(r.hasAod, r.aodStd) << ','
          << ang(r.hasAod && r.aodAmbiguous, r.aodMirror) << ',';
        const bool alt = r.hasAoa && r.hasAoaAlternative;
        char weight[32];
        std::snprintf(weight, sizeof(weight), "%.4f", r.aoaAlternativeWeight);
        f << ang(alt, r.aoaAlternative) << ',' << (alt ? weight : "") << ',';
        f << ang(alt, r.aoaDirectionStd) << ',';
        for (size_t i = 0; alt && i < r.moreAoaAlternatives.size(); ++i)
        {
            std::snprintf(
                weight, sizeof(weight), "%s%.3f:%.4f", i ? ";" : "",
                mrpt::RAD2DEG(r.moreAoaAlternatives[i].aoa), r.moreAoaAlternatives[i].weight);
            f << weight;
        }
        f << '\n';
    }
}

}  // namespace mrpt_wifi::localization
