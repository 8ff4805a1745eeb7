/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt_wifi/obs/Chanspec.h>
#include <mrpt_wifi/obs/MacAddress.h>

#include <complex>
#include <cstdint>
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
 * fftshift), as `csi[(tx * nRx + rx) * nfft + bin]`, scaled as the hardware reports it
 * (mantissa · 2^exponent). Pairs that did not arrive are flagged in `presentMask` and hold
 * zeros.
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
    /** @} */

    /** Sets the shape and zero-fills the CSI; clears presentMask. */
    void resize(unsigned nTx, unsigned nRx, unsigned nfft);

    unsigned nfft() const { return chanspec.nfft(); }
    bool isPresent(unsigned tx, unsigned rx) const
    {
        return (presentMask >> (tx * kMaxChains + rx)) & 1u;
    }
    void setPresent(unsigned tx, unsigned rx, bool present = true);
    /** Number of (tx, rx) pairs that arrived. */
    unsigned presentPairs() const;
    bool isComplete() const { return presentPairs() == unsigned(nRx) * nTx; }

    /** The NFFT bins of one (tx, rx) pair, in subcarrier order. */
    Complex* pair(unsigned tx, unsigned rx) { return csi.data() + pairOffset(tx, rx); }
    const Complex* pair(unsigned tx, unsigned rx) const { return csi.data() + pairOffset(tx, rx); }
    Complex& at(unsigned tx, unsigned rx, unsigned bin) { return pair(tx, rx)[bin]; }
    const Complex& at(unsigned tx, unsigned rx, unsigned bin) const { return pair(tx, rx)[bin]; }

    /** Data subcarrier indices k for this bandwidth (234 / 108 / 52). */
    const std::vector<int>& dataSubcarriers() const;
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
