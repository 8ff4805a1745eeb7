/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/obs/MacAddress.h>

#include <complex>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace mrpt_wifi
{
/** Which Nexmon CSI UDP header a frame arrived with (DESIGN.md §4). */
enum class NexmonHeaderVariant : uint8_t
{
    Nexmon = 0,        //!< current firmware: 2-byte magic, RSSI, frame control
    NexmonLegacy = 1,  //!< 4-byte magic, no RSSI / frame control
    UbiLocate = 2      //!< IMDEA UbiLocate firmware: core/stream masks, frame counter
};
const char* toString(NexmonHeaderVariant v);

/** Channel state information of one overheard WiFi frame: one complex number per
 *  transmit stream × receive antenna × subcarrier bin, with the frame's metadata.
 *
 * The CSI is stored in subcarrier order over all NFFT bins (bin = k + NFFT/2, i.e. after
 * fftshift), as `csi[(tx * nRx + rx) * nfft + bin]`, as the hardware reports it (raw: e.g.
 * mantissa · 2^exponent on the BCM4366c0, the int8 I/Q of an Intel 5300 or an ESP32). Pairs
 * that did not arrive are flagged in `presentMask` and hold zeros.
 *
 * Sources that report only some subcarriers (Intel 5300: 30 grouped ones; ESP32: the L-LTF or
 * HT-LTF) list them in `subcarrierIndices`; the other bins hold zeros and dataSubcarriers() returns
 * that list instead of the bandwidth's standard one. Where the source defines a scaling to
 * physical units (Intel's get_scaled_csi), `scaledCsiFactor` holds it: scaledCsi() = factor ·
 * csi.
 *
 * Serialization version 1 adds the source fields below; version 0 rawlogs (all from the
 * BCM4366c0) still load, with source = "bcm4366c0". Version 2 adds the receive chains' jump
 * states (chainDelay_ns, chainState); older rawlogs load with both empty. Version 3 adds rxCores
 * (a router reporting only some of its cores); older rawlogs load with it empty (row i = core i).
 */
class CObservationWiFiCSI : public mrpt::obs::CObservation
{
    DEFINE_SERIALIZABLE(CObservationWiFiCSI, mrpt_wifi)

public:
    using Complex = std::complex<float>;
    static constexpr unsigned kMaxChains = 8;  //!< at most 8 rx × 8 tx (presentMask bits)

    /** @name Data members
     * @{ */
    /** Pose of the receive array (its phase centre, x along the boresight) on the robot. */
    mrpt::poses::CPose3D sensorPose;
    MacAddress transmitter;        //!< 802.11 addr2 of the overheard frame
    int8_t rssi_dBm = 0;           //!< as reported by the firmware (0 when the header has none)
    uint16_t sequenceNumber = 0;   //!< 802.11 sequence number (12 bits)
    uint8_t fragmentNumber = 0;    //!< 802.11 fragment number (4 bits)
    uint8_t frameControl = 0;      //!< first byte of the 802.11 frame control (0 on the 4366c0)
    Chanspec chanspec;             //!< channel, bandwidth, band, sideband (raw word kept)
    uint16_t chipId = 0;           //!< chip version word (0x006a = BCM4366c0); 0 if not reported
    uint16_t firmwareCounter = 0;  //!< UbiLocate frame counter (0 for other headers)
    NexmonHeaderVariant headerVariant = NexmonHeaderVariant::Nexmon;
    std::string routerAddress;  //!< source IP (or "pcap"/"sim") the datagrams came from
    uint8_t nRx = 0;            //!< receive chains (cores) in the frame
    uint8_t nTx = 0;            //!< spatial streams in the frame
    uint64_t presentMask = 0;   //!< bit (tx * kMaxChains + rx) set when that pair arrived
    /** Bins (subcarrier order) that hold no measurement, e.g. firmware-overwritten ones that
     *  were masked (zeroed) rather than repaired. */
    std::vector<uint16_t> maskedBins;
    std::vector<Complex> csi;  //!< [tx][rx][bin], see class docs

    /** Radio / format that produced the frame: "bcm4366c0", "bcm43455c0", "bcm4358",
     *  "bcm4339", "iwl5300", "esp32", "sim", ... */
    std::string source = "bcm4366c0";
    /** Subcarrier indices k that carry a measurement, ascending; empty = the bandwidth's
     *  standard data subcarriers (dataSubcarriers(bandwidth), all bins measured). */
    std::vector<int16_t> subcarrierIndices;
    /** Per receive antenna RSSI [dB] as the source reports it (Intel: rssi_a/b/c, relative to
     *  the AGC); empty when not reported. */
    std::vector<float> antennaRssi_dB;
    /** Noise floor [dBm]; NaN when not reported. */
    float noiseFloor_dBm = std::numeric_limits<float>::quiet_NaN();
    /** Receiver AGC gain [dB]; NaN when not reported. */
    float agc_dB = std::numeric_limits<float>::quiet_NaN();
    /** Source-defined scaling of the raw CSI to physical units (scaledCsi() = factor · csi);
     *  0 when the format defines none. */
    double scaledCsiFactor = 0.0;
    /** Per receive chain, its delay relative to chain 0 [ns] measured on this frame (chain 0:
     *  0; NaN where too noisy to tell); empty when not measured. */
    std::vector<float> chainDelay_ns;
    /** Per receive chain, the jump state the recorder classified this frame into (ids as in
     *  the recorder's summary and, with a state-aware calibration, the calibration file's);
     *  kUnknownChainState (255) where it could not tell; empty when not classified. */
    std::vector<uint8_t> chainState;
    /** Receive core of each CSI row, ascending (row i holds core rxCores[i]) when the receiver
     *  reports only some of its cores (an RT-AC86U with core mask 0xb: rows 0, 1, 2 hold cores
     *  0, 1, 3); empty when row i is core i. Per-row vectors (chainDelay_ns, chainState,
     *  antennaRssi_dB) follow the rows. */
    std::vector<uint8_t> rxCores;
    /** @} */

    /** Sets the shape and zero-fills the CSI; clears presentMask. */
    void resize(unsigned nTx, unsigned nRx, unsigned nfft);

    unsigned nfft() const { return chanspec.nfft(); }
    bool isPresent(unsigned tx, unsigned rx) const
    {
        return (presentMask >> (tx * kMaxChains + rx)) & 1u;
    }
    void setPresent(unsigned tx, unsigned rx, bool present = true);
    /** Receive core of CSI row `row` (rxCores, or the row itself). */
    unsigned coreOfRow(unsigned row) const { return row < rxCores.size() ? rxCores[row] : row; }
    /** CSI row holding receive core `core`, or −1 when the frame has no row for it. */
    int rowOfCore(unsigned core) const;
    /** The receive cores the rows hold, e.g. "0, 1, 3". */
    std::string rowCoresAsString() const;
    /** Number of (tx, rx) pairs that arrived. */
    unsigned presentPairs() const;
    bool isComplete() const { return presentPairs() == unsigned(nRx) * nTx; }

    /** The NFFT bins of one (tx, rx) pair, in subcarrier order. */
    Complex* pair(unsigned tx, unsigned rx) { return csi.data() + pairOffset(tx, rx); }
    const Complex* pair(unsigned tx, unsigned rx) const { return csi.data() + pairOffset(tx, rx); }
    Complex& at(unsigned tx, unsigned rx, unsigned bin) { return pair(tx, rx)[bin]; }
    const Complex& at(unsigned tx, unsigned rx, unsigned bin) const { return pair(tx, rx)[bin]; }

    /** Subcarrier indices k that carry a measurement: subcarrierIndices if the source gave
     *  them, otherwise the bandwidth's data subcarriers (234 / 108 / 52). */
    std::vector<int> dataSubcarriers() const;
    /** The CSI in the source's physical units (scaledCsiFactor · csi); empty if the format
     *  defines no scaling. */
    std::vector<Complex> scaledCsi() const;
    /** Whether the source reported the subcarriers explicitly (grouped / sparse). */
    bool hasExplicitSubcarriers() const { return !subcarrierIndices.empty(); }
    /** CSI of one pair on the data subcarriers, in the order of dataSubcarriers(). */
    std::vector<Complex> dataSubcarrierCsi(unsigned tx, unsigned rx) const;
    /** Frequencies [Hz] of the data subcarriers. */
    std::vector<double> dataSubcarrierFrequencies() const;

    // CObservation interface
    void getSensorPose(mrpt::poses::CPose3D& out) const override { out = sensorPose; }
    void setSensorPose(const mrpt::poses::CPose3D& p) override { sensorPose = p; }
    void getDescriptionAsText(std::ostream& o) const override;
    bool exportTxtSupported() const override { return true; }
    std::string exportTxtHeader() const override;
    std::string exportTxtDataRow() const override;

private:
    size_t pairOffset(unsigned tx, unsigned rx) const
    {
        return (size_t(tx) * nRx + rx) * chanspec.nfft();
    }
};

}  // namespace mrpt_wifi
