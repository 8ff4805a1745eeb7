/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/config/CLoadableOptions.h>
#include <mrpt/maps/CMetricMap.h>
#include <mrpt/math/TBoundingBox.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/TransmitterMap.h>
#include <mrpt_wifi/obs/CObservationWiFiBearing.h>

#include <memory>
#include <mutex>
#include <optional>
#include <set>

namespace mrpt_wifi
{
/** A metric map of WiFi transmitters of known pose (access points), for MRPT's particle
 *  filters: it scores `mrpt_wifi::CObservationWiFiBearing` observations (AoA at the robot and
 *  AoD at the transmitter) with a robust, mirror-aware bearing model
 *  (localization::RobustBearingModel) and returns 0 (log-likelihood) for anything else, so it
 *  can sit in a CMultiMetricMap beside other maps.
 *
 * Use from any MRPT .ini (pf-localization, wifi-pf-localization):
 * \code
 * [MetricMap]
 * wifiBearingMap_count = 1
 *
 * [MetricMap_wifiBearingMap_00_creationOpts]
 * transmitters_file = /path/to/transmitters.yaml   ; see TransmitterMap (YAML)
 * ; optional: the area the robot can be in (all four or none). Without them the area is the
 * ; [LocalizationExperiment] init_PDF box of a uniform start (init_PDF_mode = 1) of the same
 * ; file, where a kidnapped robot may be: one source of truth (see areaFromInitialPdf()).
 * min_x = 0
 * max_x = 10
 * min_y = 0
 * max_y = 5
 *
 * [MetricMap_wifiBearingMap_00_likelihoodOpts]
 * use_aoa = true
 * use_aod = true
 * outlier_prob = 0.1
 * min_std_deg = 2
 * std_scale = 1.0
 * max_std_deg = 45
 * bearing_weight = 1   ; (0, 1]: tempers each bearing's log-likelihood (see bearingWeight)
 * aoa_alternative_share = 0   ; [0, 1]: > 0 weighs a bearing's alternative directions too,
 *                             ; their measured weights × this
 * (RobustBearingModel::aoaAlternativeShare) \endcode The map is read-only: inserting observations
 * does nothing (it is built from the file).
 *
 * With an area, a pose outside it scores kOutsideAreaLogLikelihood per bearing whatever the
 * bearings say: a particle filter's particles that leave the building lose their weight at the
 * next step and are not resampled (the robot can't be there).
 */
class CWiFiBearingMap : public mrpt::maps::CMetricMap
{
    DEFINE_SERIALIZABLE(CWiFiBearingMap, mrpt_wifi)

public:
    CWiFiBearingMap() = default;

    /** Likelihood options (section `..._likelihoodOpts`). */
    struct TLikelihoodOptions : public mrpt::config::CLoadableOptions
    {
        localization::RobustBearingModel model;
        localization::BearingUse use;
        /** `bearing_weight` in (0, 1]: each bearing's log-likelihood is multiplied by it (a
         *  tempered likelihood). Bearings taken a fraction of a second apart err alike (the
         *  multipath at that spot), so counting each as independent evidence makes the filter
         *  sure of a pose long before the robot has moved far enough to average the multipath
         *  out: its particles collapse onto the first pose that fits and cannot leave. 1: each
         *  bearing counts fully (MRPT's usual product of likelihoods). */
        double bearingWeight = 1.0;
        void loadFromConfigFile(
            const mrpt::config::CConfigFileBase& source, const std::string& section) override;
        void dumpToTextStream(std::ostream& out) const override;
    } likelihoodOptions;

    /** Replaces the transmitters. */
    void setTransmitters(const localization::TransmitterMap& m) { transmitters_ = m; }
    const localization::TransmitterMap& transmitters() const { return transmitters_; }
    /** Loads the transmitters from a YAML file (throws with the file and reason). */
    void loadTransmitters(const std::string& yamlFile);

    /** The area the robot can be in (x and y of the box; z unused), or none (unbounded). */
    void setArea(const std::optional<mrpt::math::TBoundingBox>& area)
    {
        area_ = area;
        areaFromInitPdf_ = false;
    }
    const std::optional<mrpt::math::TBoundingBox>& area() const { return area_; }
    /** The area was not given in the creationOpts: it is the .ini's init_PDF box (set by the
     *  map definition; setArea() clears it). */
    bool areaFromInitialPdf() const { return areaFromInitPdf_; }
    bool inArea(double x, double y) const { return inArea(area_, x, y); }
    /** (x, y) inside `area` (x and y of the box), or no area. */
    static bool inArea(const std::optional<mrpt::math::TBoundingBox>& area, double x, double y)
    {
        return !area ||
               (x >= area->min.x && x <= area->max.x && y >= area->min.y && y <= area->max.y);
    }
    /** Log-likelihood of one bearing seen from a pose outside the area: e^-30, far below any
     *  bearing's own (the robust model's outlier floor is ≈ log(0.1/2π) = −4.1). */
    static constexpr double kOutsideAreaLogLikelihood = -30.0;

    /** Whether a bearing agrees with a robot pose (localization::recordAgrees with this map's
     *  model; within `nSigma` σ); nullopt for an unknown transmitter or no usable angle. */
    std::optional<bool> agrees(
        const CObservationWiFiBearing& b, const mrpt::math::TPose2D& robot,
        double nSigma = 3.0) const;

    /** Observations whose transmitter isn't in the map (counted once per observation object
     *  and MAC seen, not per particle) and the MACs involved. */
    size_t unknownTransmitterCount() const;
    std::set<MacAddress> unknownTransmitters() const;

    // CMetricMap
    bool isEmpty() const override { return transmitters_.empty(); }
    void saveMetricMapRepresentationToFile(const std::string& filNamePrefix) const override;
    std::string asString() const override;
    void getVisualizationInto(mrpt::opengl::CSetOfObjects& o) const override;

    MAP_DEFINITION_START(CWiFiBearingMap)
    std::string transmittersFile;  //!< `transmitters_file` in `..._creationOpts`
    /** `min_x`, `max_x`, `min_y`, `max_y` in `..._creationOpts` (all four or none) */
    std::optional<mrpt::math::TBoundingBox> area;
    /** No area in `..._creationOpts`: `area` is the `[LocalizationExperiment]` init_PDF box */
    bool areaFromInitialPdf = false;
    std::string areaError;  //!< a malformed area, reported when the map is created
    std::string keyError;   //!< an unknown key, reported when the map is created
    /** a bad `..._likelihoodOpts` value, reported when the map is created */
    std::string likelihoodError;
    CWiFiBearingMap::TLikelihoodOptions likelihoodOpts;
    MAP_DEFINITION_END(CWiFiBearingMap)

private:
    localization::TransmitterMap transmitters_;
    std::optional<mrpt::math::TBoundingBox> area_;
    bool areaFromInitPdf_ = false;
    /** Bookkeeping of unknown transmitters, shared so the map stays copyable (clone()). */
    struct UnknownLog
    {
        std::mutex mtx;
        std::set<MacAddress> macs;
        size_t count = 0;
        const void* lastObs = nullptr;
    };
    std::shared_ptr<UnknownLog> unknown_ = std::make_shared<UnknownLog>();

    void internal_clear() override {}
    bool internal_insertObservation(
        const mrpt::obs::CObservation& obs,
        const std::optional<const mrpt::poses::CPose3D>& robotPose) override;
    double internal_computeObservationLikelihood(
        const mrpt::obs::CObservation& obs, const mrpt::poses::CPose3D& takenFrom) const override;
    bool internal_canComputeObservationLikelihood(
        const mrpt::obs::CObservation& obs) const override;
    void noteUnknown(const mrpt::obs::CObservation& obs, const MacAddress& mac) const;
};

}  // namespace mrpt_wifi
