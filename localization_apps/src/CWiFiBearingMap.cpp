/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/maps/TMetricMapTypesRegistry.h>
#include <mrpt/opengl/CSetOfObjects.h>
#include <mrpt/opengl/CText.h>
#include <mrpt/opengl/stock_objects.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/localization/IniValues.h>
#include <mrpt_wifi/localization/LiveLocalizer.h>  // initialPdfArea
#include <mrpt_wifi/obs/BoundedArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>
#include <mrpt_wifi/obs/ConfigKeys.h>
#include <mrpt_wifi/obs/ConfigPaths.h>

#include <fstream>
#include <iostream>
#include <sstream>

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

// Both names work in a [MetricMap] section: `wifiBearingMap_count=1` is the short one.
MAP_DEFINITION_REGISTER("mrpt_wifi::CWiFiBearingMap,wifiBearingMap", mrpt_wifi::CWiFiBearingMap)

IMPLEMENTS_SERIALIZABLE(CWiFiBearingMap, mrpt::maps::CMetricMap, mrpt_wifi)

// ---------------------------------------------------------------- map definition (.ini)
CWiFiBearingMap::TMapDefinition::TMapDefinition() = default;

void CWiFiBearingMap::TMapDefinition::loadFromConfigFile_map_specific(
    const mrpt::config::CConfigFileBase& source, const std::string& prefix)
{
    const std::string sect = prefix + "_creationOpts";
    keyError.clear();
    try
    {
        config::requireKnownKeys(
            source, sect, config::sectionKeys("MetricMap_wifiBearingMap_NN_creationOpts"));
    }
    catch (const std::invalid_argument& e)
    {
        keyError = e.what();  // reported when the map is created, as the area's errors
    }
    transmittersFile = source.read_string(sect, "transmitters_file", "");
    // Relative: from the .ini's folder (found also when Debian's pf-localization reads it),
    // else the working directory, else the data folder (mrpt_wifi/obs/ConfigPaths.h).
    try
    {
        const auto r = config::resolveConfigPath(
            transmittersFile, config::iniDirectory(source, sect), "localization",
            "[" + sect + "] transmitters_file");
        if (!r.note.empty()) std::cerr << "note: " << r.note << "\n";
        transmittersFile = r.path;
    }
    catch (const std::invalid_argument&)
    {
        // kept as written: creating the map names the file it cannot read
    }
    const char* keys[] = {"min_x", "max_x", "min_y", "max_y"};
    size_t given = 0;
    for (const char* k : keys) given += source.keyExists(sect, k) ? 1 : 0;
    area.reset();
    areaFromInitialPdf = false;
    areaError.clear();
    // Errors wait for the map's creation: MRPT's loader leaks a definition that throws here.
    try
    {
        requireIniNumbers(source, sect, {"min_x", "max_x", "min_y", "max_y"});
    }
    catch (const std::invalid_argument& e)
    {
        areaError = e.what();
    }
    if (areaError.empty())  // else reported when the map is created
    {
        if (given == 4)
        {
            const auto rd = [&](const char* k) { return source.read_double(sect, k, 0); };
            area = mrpt::math::TBoundingBox(
                {rd("min_x"), rd("min_y"), 0}, {rd("max_x"), rd("max_y"), 0},
                mrpt::math::TBoundingBox::CTOR_FLAGS::AllowUnordered);
            if (!(area->max.x > area->min.x) || !(area->max.y > area->min.y))
                areaError = "[" + sect + "] the area needs min_x < max_x and min_y < max_y";
        }
        else if (given != 0)
            areaError =
                "[" + sect +
                "] min_x, max_x, min_y, max_y: give all four (the area the robot can be in) "
                "or none";
        else
        {
            // One source of truth: the area is where a kidnapped robot may start, in every program
            // that builds the map from this file (Debian's pf-localization too).
            try
            {
                area = localization::initialPdfArea(source);
                areaFromInitialPdf = area.has_value();
            }
            catch (const std::invalid_argument& e)
            {
                areaError = e.what();
            }
        }
    }
    likelihoodError.clear();
    try
    {
        likelihoodOpts.loadFromConfigFile(source, prefix + "_likelihoodOpts");
    }
    catch (const std::exception& e)
    {
        likelihoodError = e.what();  // reported when the map is created, as the area's errors
    }
}

void CWiFiBearingMap::TMapDefinition::dumpToTextStream_map_specific(std::ostream& out) const
{
    out << "transmitters_file = " << transmittersFile << "\n";
    if (area)
        out << "min_x = " << area->min.x << "\nmax_x = " << area->max.x
            << "\nmin_y = " << area->min.y << "\nmax_y = " << area->max.y << "\n";
    likelihoodOpts.dumpToTextStream(out);
}

mrpt::maps::CMetricMap* CWiFiBearingMap::internal_CreateFromMapDefinition(
    const mrpt::maps::TMetricMapInitializer& _def)
{
    const auto& def = dynamic_cast<const CWiFiBearingMap::TMapDefinition&>(_def);
    auto* map = new CWiFiBearingMap();
    map->likelihoodOptions = def.likelihoodOpts;
    map->area_ = def.area;
    map->areaFromInitPdf_ = def.areaFromInitialPdf;
    if (!def.keyError.empty())
    {
        delete map;
        throw std::invalid_argument(def.keyError);
    }
    if (!def.areaError.empty())
    {
        delete map;
        throw std::invalid_argument(def.areaError);
    }
    if (!def.likelihoodError.empty())
    {
        delete map;
        throw std::invalid_argument(def.likelihoodError);
    }
    if (def.transmittersFile.empty())
    {
        delete map;
        throw std::runtime_error(
            "CWiFiBearingMap: 'transmitters_file' is missing in the map's _creationOpts section");
    }
    try
    {
        map->loadTransmitters(def.transmittersFile);
    }
    catch (...)
    {
        delete map;
        throw;
    }
    return map;
}

void CWiFiBearingMap::TLikelihoodOptions::loadFromConfigFile(
    const mrpt::config::CConfigFileBase& c, const std::string& s)
{
    config::requireKnownKeys(
        c, s, config::sectionKeys("MetricMap_wifiBearingMap_NN_likelihoodOpts"));
    requireIniBools(c, s, {"use_aoa", "use_aod"});
    requireIniNumbers(
        c, s,
        {"outlier_prob", "min_std_deg", "max_std_deg", "std_scale", "aoa_alternative_share",
         "bearing_weight"});
    use.aoa = c.read_bool(s, "use_aoa", use.aoa);
    use.aod = c.read_bool(s, "use_aod", use.aod);
    model.outlierProb = c.read_double(s, "outlier_prob", model.outlierProb);
    model.minStd_rad =
        mrpt::DEG2RAD(c.read_double(s, "min_std_deg", mrpt::RAD2DEG(model.minStd_rad)));
    model.maxStd_rad =
        mrpt::DEG2RAD(c.read_double(s, "max_std_deg", mrpt::RAD2DEG(model.maxStd_rad)));
    model.stdScale = c.read_double(s, "std_scale", model.stdScale);
    model.aoaAlternativeShare =
        c.read_double(s, "aoa_alternative_share", model.aoaAlternativeShare);
    bearingWeight = c.read_double(s, "bearing_weight", bearingWeight);
    if (!(model.outlierProb > 0 && model.outlierProb < 1))
        throw std::invalid_argument("[" + s + "] outlier_prob must be in (0, 1)");
    if (!(model.minStd_rad > 0) || !(model.stdScale > 0))
        throw std::invalid_argument("[" + s + "] min_std_deg and std_scale must be > 0");
    if (!(bearingWeight > 0 && bearingWeight <= 1))
        throw std::invalid_argument("[" + s + "] bearing_weight must be in (0, 1]");
    if (!(model.aoaAlternativeShare >= 0 && model.aoaAlternativeShare <= 1))
        throw std::invalid_argument("[" + s + "] aoa_alternative_share must be in [0, 1]");
    // A filter on such a map runs without error and never moves from its prior.
    if (!use.aoa && !use.aod)
        throw std::invalid_argument(
            "[" + s + "] use_aoa and use_aod are both false: the map would weigh no bearing");
}

void CWiFiBearingMap::TLikelihoodOptions::dumpToTextStream(std::ostream& out) const
{
    out << "use_aoa = " << use.aoa << "\nuse_aod = " << use.aod
        << "\noutlier_prob = " << model.outlierProb
        << "\nmin_std_deg = " << mrpt::RAD2DEG(model.minStd_rad)
        << "\nmax_std_deg = " << mrpt::RAD2DEG(model.maxStd_rad)
        << "\nstd_scale = " << model.stdScale << "\nbearing_weight = " << bearingWeight
        << "\naoa_alternative_share = " << model.aoaAlternativeShare << "\n";
}

// ---------------------------------------------------------------- the map
void CWiFiBearingMap::loadTransmitters(const std::string& yamlFile)
{
    transmitters_ = TransmitterMap::fromYamlFile(yamlFile);
    if (transmitters_.empty())
        throw std::runtime_error(yamlFile + ": the transmitter map is empty");
}

size_t CWiFiBearingMap::unknownTransmitterCount() const
{
    std::lock_guard<std::mutex> lk(unknown_->mtx);
    return unknown_->count;
}

std::set<MacAddress> CWiFiBearingMap::unknownTransmitters() const
{
    std::lock_guard<std::mutex> lk(unknown_->mtx);
    return unknown_->macs;
}

void CWiFiBearingMap::noteUnknown(const mrpt::obs::CObservation& obs, const MacAddress& mac) const
{
    // Called once per particle: count each observation object once, warn once per MAC.
    std::lock_guard<std::mutex> lk(unknown_->mtx);
    if (unknown_->lastObs == &obs) return;
    unknown_->lastObs = &obs;
    unknown_->count++;
    if (unknown_->macs.insert(mac).second)
        std::cerr << "[CWiFiBearingMap] warning: bearings of transmitter " << mac.asString()
                  << " which is not in the map: ignored (counted)\n";
}

bool CWiFiBearingMap::internal_insertObservation(
    const mrpt::obs::CObservation&, const std::optional<const mrpt::poses::CPose3D>&)
{
    return false;  // built from the transmitters file, not from observations
}

bool CWiFiBearingMap::internal_canComputeObservationLikelihood(
    const mrpt::obs::CObservation& obs) const
{
    return IS_CLASS(obs, CObservationWiFiBearing);
}

double CWiFiBearingMap::internal_computeObservationLikelihood(
    const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& takenFrom) const
{
    if (!IS_CLASS(obs, CObservationWiFiBearing)) return 0;
    const auto& o = static_cast<const CObservationWiFiBearing&>(obs);
    const KnownTransmitter* tx = transmitters_.find(o.transmitter);
    if (!tx)
    {
        noteUnknown(obs, o.transmitter);
        return 0;
    }
    if (!inArea(takenFrom.x(), takenFrom.y())) return kOutsideAreaLogLikelihood;
    const mrpt::math::TPose2D robot(takenFrom.x(), takenFrom.y(), takenFrom.yaw());
    return likelihoodOptions.bearingWeight * recordLogLikelihood(
                                                 recordFromObservation(o), robot, *tx,
                                                 likelihoodOptions.model, likelihoodOptions.use);
}

std::optional<bool> CWiFiBearingMap::agrees(
    const CObservationWiFiBearing& b, const mrpt::math::TPose2D& robot, double nSigma) const
{
    const KnownTransmitter* tx = transmitters_.find(b.transmitter);
    if (!tx) return std::nullopt;
    return recordAgrees(
        recordFromObservation(b), robot, *tx, likelihoodOptions.model, likelihoodOptions.use,
        nSigma);
}

void CWiFiBearingMap::saveMetricMapRepresentationToFile(const std::string& prefix) const
{
    std::ofstream f(prefix + "_transmitters.yaml");
    f << transmitters_.asYamlText();
}

std::string CWiFiBearingMap::asString() const
{
    std::string s =
        "CWiFiBearingMap with " + std::to_string(transmitters_.size()) + " transmitters";
    if (area_)
    {
        std::ostringstream o;
        o << ", area x " << area_->min.x << ".." << area_->max.x << " y " << area_->min.y << ".."
          << area_->max.y << " m";
        s += o.str();
    }
    return s;
}

void CWiFiBearingMap::getVisualizationInto(mrpt::opengl::CSetOfObjects& o) const
{
    if (!genericMapParams.enableSaveAs3DObject) return;
    for (const auto& t : transmitters_.transmitters())
    {
        auto corner = mrpt::opengl::stock_objects::CornerXYSimple(0.5f, 2.0f);
        corner->setPose(mrpt::poses::CPose3D(t.pose.x, t.pose.y, 0, t.pose.phi, 0, 0));
        o.insert(corner);
        auto label = mrpt::opengl::CText::Create(t.name);
        label->setLocation(t.pose.x, t.pose.y, 0.3);
        o.insert(label);
    }
}

// ---------------------------------------------------------------- serialization
uint8_t CWiFiBearingMap::serializeGetVersion() const
{
    return 3;  // 1: the area; 2: the bearing weight; 3: the AoA alternative's share
}

void CWiFiBearingMap::serializeTo(mrpt::serialization::CArchive& out) const
{
    out << transmitters_.asYamlText();
    const auto& m = likelihoodOptions.model;
    out << m.outlierProb << m.minStd_rad << m.stdScale << m.maxStd_rad << likelihoodOptions.use.aoa
        << likelihoodOptions.use.aod;
    out << genericMapParams;
    out << area_.has_value();
    if (area_) out << area_->min.x << area_->max.x << area_->min.y << area_->max.y;
    out << likelihoodOptions.bearingWeight;
    out << likelihoodOptions.model.aoaAlternativeShare;
}

void CWiFiBearingMap::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
    switch (version)
    {
        case 0:
        case 1:
        case 2:
        case 3:
        {
            std::string yaml;
            // A map of thousands of transmitters is well below 64 MB of YAML.
            readBoundedString(in, yaml, 64u << 20, "CWiFiBearingMap");
            transmitters_ = TransmitterMap::fromYamlText(yaml, "<serialized CWiFiBearingMap>");
            auto& m = likelihoodOptions.model;
            in >> m.outlierProb >> m.minStd_rad >> m.stdScale >> m.maxStd_rad >>
                likelihoodOptions.use.aoa >> likelihoodOptions.use.aod;
            in >> genericMapParams;
            area_.reset();
            bool hasArea = false;
            if (version >= 1) in >> hasArea;
            if (hasArea)
            {
                mrpt::math::TBoundingBox b;
                in >> b.min.x >> b.max.x >> b.min.y >> b.max.y;
                area_ = b;
            }
            likelihoodOptions.bearingWeight = 1.0;
            if (version >= 2) in >> likelihoodOptions.bearingWeight;
            if (!(likelihoodOptions.bearingWeight > 0 && likelihoodOptions.bearingWeight <= 1))
                throw std::runtime_error(
                    "serialized CWiFiBearingMap: bearing weight " +
                    std::to_string(likelihoodOptions.bearingWeight) + " is outside (0, 1]");
            m.aoaAlternativeShare = 0;
            if (version >= 3) in >> m.aoaAlternativeShare;
            if (!(m.aoaAlternativeShare >= 0 && m.aoaAlternativeShare <= 1))
                throw std::runtime_error(
                    "serialized CWiFiBearingMap: AoA alternative share " +
                    std::to_string(m.aoaAlternativeShare) + " is outside [0, 1]");
        }
        break;
        default:
            MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
    }
}
