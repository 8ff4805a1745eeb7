/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/localization/BearingRecord.h>
#include <mrpt_wifi/localization/TransmitterMap.h>

#include <cstdint>
#include <string>
#include <vector>

namespace mrpt_wifi::localization
{
/** "Bearings from elsewhere" for development and tests: turns the simulator's true angles
 *  (`frames.csv` of `wifi-sim --truth-dir`) into what a decent external CSI tool would report.
 *  This is NOT an estimator: it adds a stated error model to the truth. */
struct SyntheticBearingOptions
{
    double aoaStd_rad = 0.0524;     //!< Gaussian error σ of AoA (3°), also the reported σ
    double aodStd_rad = 0.0698;     //!< of AoD (4°)
    double outlierFraction = 0.03;  //!< angles replaced by uniform ones
    /** Where the simulator says the strongest path is not the line of sight, report the
     *  strongest path's AoA (what a naive peak picker does under multipath). */
    bool strongestPathErrors = true;
    double rate_Hz = 10;    //!< per-transmitter cap (0: every frame)
    bool aod = true;        //!< AoD for transmitters with ≥ 2 array elements
    ArrayGeometry rxArray;  //!< robot array: linear ⇒ reports a mirror candidate
    uint64_t seed = 1;
};

struct SyntheticBearingStats
{
    size_t frames = 0, kept = 0, outliers = 0, strongestPath = 0, unknownTransmitter = 0;
};

/** Reads frames.csv; `transmitters` (the simulator's transmitters.yaml) gives the transmit
 *  arrays. Throws std::runtime_error on a malformed file. */
std::vector<BearingRecord> synthesizeBearings(
    const std::string& framesCsv, const TransmitterMap& transmitters,
    const SyntheticBearingOptions& options, SyntheticBearingStats* stats = nullptr);

}  // namespace mrpt_wifi::localization
