/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/datetime.h>
#include <mrpt_wifi/obs/BoundedArchive.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/ChainStates.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <cmath>
#include <iomanip>
#include <sstream>

using namespace mrpt_wifi;

IMPLEMENTS_SERIALIZABLE(CObservationWiFiCSI, mrpt::obs::CObservation, mrpt_wifi)

const char* mrpt_wifi::toString(NexmonHeaderVariant v)
{
    switch (v)
    {
        case NexmonHeaderVariant::Nexmon:
            return "nexmon";
        case NexmonHeaderVariant::NexmonLegacy:
            return "nexmon-legacy";
        case NexmonHeaderVariant::UbiLocate:
            return "ubilocate";
    }
    return "unknown";
}

void CObservationWiFiCSI::resize(unsigned numTx, unsigned numRx, unsigned nfftBins)
{
    ASSERT_LE_(numTx, kMaxChains);
    ASSERT_LE_(numRx, kMaxChains);
    ASSERT_EQUAL_(nfftBins, chanspec.nfft());
    nTx = uint8_t(numTx);
    nRx = uint8_t(numRx);
    presentMask = 0;
    csi.assign(size_t(numTx) * numRx * nfftBins, Complex(0, 0));
}

void CObservationWiFiCSI::setPresent(unsigned tx, unsigned rx, bool present)
{
    const uint64_t bit = uint64_t(1) << (tx * kMaxChains + rx);
    presentMask = present ? (presentMask | bit) : (presentMask & ~bit);
}

unsigned CObservationWiFiCSI::presentPairs() const
{
    return unsigned(__builtin_popcountll(presentMask));
}

std::vector<int> CObservationWiFiCSI::dataSubcarriers() const
{
    if (subcarrierIndices.empty()) return mrpt_wifi::dataSubcarriers(chanspec.bandwidthMHz);
    return {subcarrierIndices.begin(), subcarrierIndices.end()};
}

std::vector<CObservationWiFiCSI::Complex> CObservationWiFiCSI::scaledCsi() const
{
    std::vector<Complex> out;
    if (scaledCsiFactor == 0.0) return out;
    out.reserve(csi.size());
    const auto f = float(scaledCsiFactor);
    for (const auto& h : csi) out.push_back(h * f);
    return out;
}

std::vector<CObservationWiFiCSI::Complex> CObservationWiFiCSI::dataSubcarrierCsi(
    unsigned tx, unsigned rx) const
{
    const auto ks = dataSubcarriers();
    const unsigned n = nfft();
    const Complex* p = pair(tx, rx);
    std::vector<Complex> out;
    out.reserve(ks.size());
    for (int k : ks) out.push_back(p[subcarrierToBin(k, n)]);
    return out;
}

std::vector<double> CObservationWiFiCSI::dataSubcarrierFrequencies() const
{
    std::vector<double> f;
    for (int k : dataSubcarriers()) f.push_back(subcarrierFrequencyHz(chanspec, k));
    return f;
}

// ---------------------------------------------------------------- serialization
// Version 0: the BCM4366c0 fields. Version 1 (issue 13): + source, subcarrierIndices,
// antennaRssi_dB, noiseFloor_dBm, agc_dB, scaledCsiFactor. Version 2 (issue 21): + chainDelay_ns,
// chainState. Version 3 (issue 54): + rxCores.
uint8_t CObservationWiFiCSI::serializeGetVersion() const
{
    return 3;
}

int CObservationWiFiCSI::rowOfCore(unsigned core) const
{
    if (rxCores.empty()) return core < nRx ? int(core) : -1;
    for (size_t i = 0; i < rxCores.size() && i < nRx; ++i)
        if (rxCores[i] == core) return int(i);
    return -1;
}

std::string CObservationWiFiCSI::rowCoresAsString() const
{
    std::string s;
    for (unsigned i = 0; i < nRx; ++i) s += (i ? ", " : "") + std::to_string(coreOfRow(i));
    return s;
}

void CObservationWiFiCSI::serializeTo(mrpt::serialization::CArchive& out) const
{
    out << timestamp << sensorLabel << sensorPose;
    out.WriteBuffer(transmitter.bytes.data(), transmitter.bytes.size());
    out << rssi_dBm << sequenceNumber << fragmentNumber << frameControl << chanspec.raw << chipId
        << firmwareCounter << uint8_t(headerVariant) << routerAddress << nRx << nTx << presentMask;
    out << maskedBins;
    out.WriteAs<uint32_t>(csi.size());
    // std::complex<float> is two contiguous floats by the standard: write them as such.
    out.WriteBufferFixEndianness(reinterpret_cast<const float*>(csi.data()), csi.size() * 2);
    // version 1
    out << source << subcarrierIndices << antennaRssi_dB << noiseFloor_dBm << agc_dB
        << scaledCsiFactor;
    // version 2
    out << chainDelay_ns << chainState;
    // version 3
    out << rxCores;
}

void CObservationWiFiCSI::serializeFrom(mrpt::serialization::CArchive& in, uint8_t version)
{
    switch (version)
    {
        case 0:
        case 1:
        case 2:
        case 3:
        {
            // Strings and vectors are read with a bound: a damaged length must not ask for
            // gigabytes (MRPT's own readers allocate whatever the file claims).
            constexpr const char* kWhat = "CObservationWiFiCSI";
            in >> timestamp;
            readBoundedString(in, sensorLabel, kMaxStoredStringLength, kWhat);
            in >> sensorPose;
            in.ReadBuffer(transmitter.bytes.data(), transmitter.bytes.size());
            uint16_t rawChanspec = 0;
            uint8_t variant = 0;
            in >> rssi_dBm >> sequenceNumber >> fragmentNumber >> frameControl >> rawChanspec >>
                chipId >> firmwareCounter >> variant;
            readBoundedString(in, routerAddress, kMaxStoredStringLength, kWhat);
            in >> nRx >> nTx >> presentMask;
            const auto cs = Chanspec::decode(rawChanspec);
            if (!cs)
                THROW_EXCEPTION_FMT(
                    "CObservationWiFiCSI: stored chanspec 0x%04x is invalid", rawChanspec);
            chanspec = *cs;
            if (variant > uint8_t(NexmonHeaderVariant::UbiLocate))
                THROW_EXCEPTION_FMT("CObservationWiFiCSI: unknown header variant %u", variant);
            headerVariant = NexmonHeaderVariant(variant);
            readBoundedVector(in, maskedBins, chanspec.nfft(), kWhat);
            const uint32_t n = in.ReadAs<uint32_t>();
            if (nRx > kMaxChains || nTx > kMaxChains || n != size_t(nRx) * nTx * chanspec.nfft())
                THROW_EXCEPTION_FMT(
                    "CObservationWiFiCSI: stored CSI has %u values, expected %u tx x %u rx x %u", n,
                    nTx, nRx, chanspec.nfft());
            csi.resize(n);
            in.ReadBufferFixEndianness(reinterpret_cast<float*>(csi.data()), size_t(n) * 2);
            if (version >= 1)
            {
                readBoundedString(in, source, kMaxStoredStringLength, kWhat);
                readBoundedVector(in, subcarrierIndices, chanspec.nfft(), kWhat);
                readBoundedVector(in, antennaRssi_dB, kMaxChains, kWhat);
                in >> noiseFloor_dBm >> agc_dB >> scaledCsiFactor;
                const int half = int(chanspec.nfft() / 2);
                for (auto k : subcarrierIndices)
                    if (k < -half || k >= half)
                        THROW_EXCEPTION_FMT(
                            "CObservationWiFiCSI: stored subcarrier %d outside a %u-point FFT",
                            int(k), chanspec.nfft());
            }
            else
            {
                // Version 0 was written only for the BCM4366c0 (RT-AC86U) and the simulator.
                source = "bcm4366c0";
                subcarrierIndices.clear();
                antennaRssi_dB.clear();
                noiseFloor_dBm = agc_dB = std::numeric_limits<float>::quiet_NaN();
                scaledCsiFactor = 0.0;
            }
            chainDelay_ns.clear();
            chainState.clear();
            if (version >= 2)
            {
                readBoundedVector(in, chainDelay_ns, kMaxChains, kWhat);
                readBoundedVector(in, chainState, kMaxChains, kWhat);
            }
            rxCores.clear();
            if (version >= 3)
            {
                readBoundedVector(in, rxCores, kMaxChains, kWhat);
                if (!rxCores.empty() && rxCores.size() != nRx)
                    THROW_EXCEPTION_FMT(
                        "CObservationWiFiCSI: stored receive cores list %u rows, the CSI has %u",
                        unsigned(rxCores.size()), unsigned(nRx));
                for (size_t i = 0; i < rxCores.size(); ++i)
                    if (rxCores[i] >= kMaxChains || (i > 0 && rxCores[i] <= rxCores[i - 1]))
                        THROW_EXCEPTION(
                            "CObservationWiFiCSI: stored receive cores are not ascending core "
                            "numbers below 8");
            }
        }
        break;
        default:
            MRPT_THROW_UNKNOWN_SERIALIZATION_VERSION(version);
    }
}

// ---------------------------------------------------------------- human-readable views
namespace
{
struct PairSummary
{
    double meanMagnitude_dB = 0;  //!< 20·log10 of the mean |h| over data subcarriers
    double phaseSlope_rad = 0;    //!< mean phase step between adjacent data subcarriers
};

PairSummary summarize(const CObservationWiFiCSI& o, unsigned tx, unsigned rx)
{
    const auto ks = o.dataSubcarriers();
    const unsigned n = o.nfft();
    const auto* p = o.pair(tx, rx);
    double sumMag = 0;
    std::complex<double> stepSum{0, 0};
    for (size_t i = 0; i < ks.size(); ++i)
    {
        const std::complex<double> h = p[subcarrierToBin(ks[i], n)];
        sumMag += std::abs(h);
        if (i > 0 && ks[i] == ks[i - 1] + 1)
            stepSum += h * std::conj(std::complex<double>(p[subcarrierToBin(ks[i - 1], n)]));
    }
    PairSummary s;
    const double mean = sumMag / double(ks.size());
    s.meanMagnitude_dB =
        mean > 0 ? 20.0 * std::log10(mean) : -std::numeric_limits<double>::infinity();
    s.phaseSlope_rad = std::arg(stepSum);
    return s;
}
}  // namespace

void CObservationWiFiCSI::getDescriptionAsText(std::ostream& o) const
{
    CObservation::getDescriptionAsText(o);
    o << "WiFi CSI frame from " << source << "\n";
    o << "  Transmitter MAC      : " << transmitter.asString() << "\n";
    o << "  RSSI                 : ";
    if (source == "iwl5300" || source == "esp32")
        o << int(rssi_dBm) << " dBm\n";
    else if (headerVariant == NexmonHeaderVariant::Nexmon)
        o << int(rssi_dBm) << " dBm\n";
    else
        o << "not reported by the " << toString(headerVariant) << " header\n";
    o << "  Sequence / fragment  : " << sequenceNumber << " / " << int(fragmentNumber) << "\n";
    o << "  Frame control        : 0x" << std::hex << std::setw(2) << std::setfill('0')
      << int(frameControl) << std::dec << std::setfill(' ') << "\n";
    o << "  Chanspec             : 0x" << std::hex << std::setw(4) << std::setfill('0')
      << chanspec.raw << std::dec << std::setfill(' ') << " = channel "
      << int(chanspec.centerChannel) << " / " << chanspec.bandwidthMHz << " MHz, "
      << (chanspec.band == WifiBand::Band5G ? "5 GHz" : "2.4 GHz") << ", control channel "
      << chanspec.controlChannel() << " (sideband " << int(chanspec.sideband) << "), center "
      << std::fixed << std::setprecision(1) << chanspec.centerFrequencyHz() * 1e-6 << " MHz\n";
    o << "  Chip / header        : 0x" << std::hex << std::setw(4) << std::setfill('0') << chipId
      << std::dec << std::setfill(' ') << " / " << toString(headerVariant);
    if (headerVariant == NexmonHeaderVariant::UbiLocate)
        o << " (firmware counter " << firmwareCounter << ")";
    o << "\n  Router address       : " << routerAddress << "\n";
    o << "  Sensor pose on robot : " << sensorPose.asString() << "\n";
    if (!antennaRssi_dB.empty())
    {
        o << "  RSSI per antenna [dB]:";
        for (float r : antennaRssi_dB) o << " " << r;
        o << "\n";
    }
    if (!std::isnan(noiseFloor_dBm)) o << "  Noise floor          : " << noiseFloor_dBm << " dBm\n";
    if (!std::isnan(agc_dB)) o << "  AGC gain             : " << agc_dB << " dB\n";
    if (scaledCsiFactor != 0.0)
        o << "  Scaled CSI           : raw x " << std::setprecision(6) << scaledCsiFactor
          << " (the source's own scaling)\n";
    if (!subcarrierIndices.empty())
        o << "  Subcarriers          : " << subcarrierIndices.size() << " reported ("
          << subcarrierIndices.front() << " .. " << subcarrierIndices.back() << ")\n";
    o << "  Shape                : " << int(nTx) << " tx x " << int(nRx) << " rx x " << nfft()
      << " bins (" << dataSubcarriers().size() << " data subcarriers), " << presentPairs() << "/"
      << int(nTx) * int(nRx) << " pairs present\n";
    if (!rxCores.empty())
        o << "  Receive cores        : " << rowCoresAsString() << " (rx i below is the i-th)\n";
    if (!maskedBins.empty())
    {
        o << "  Masked bins (k)      :";
        for (auto b : maskedBins) o << " " << binToSubcarrier(b, nfft());
        o << "\n";
    }
    if (!chainDelay_ns.empty() || !chainState.empty())
    {
        // The BCM4366c0's inter-chain delay jumps among a few states (steps of ~3 ns).
        o << "  Receive chain states : ";
        for (size_t rx = 1; rx < std::max(chainDelay_ns.size(), chainState.size()); ++rx)
        {
            o << (rx > 1 ? ", " : "") << "chain " << rx << " ";
            if (rx < chainState.size())
            {
                if (chainState[rx] == kUnknownChainState)
                    o << "state ?";
                else
                    o << "state " << int(chainState[rx]);
            }
            if (rx < chainDelay_ns.size() && std::isfinite(chainDelay_ns[rx]))
                o << " (" << std::showpos << std::fixed << std::setprecision(2) << chainDelay_ns[rx]
                  << std::noshowpos << " ns)";
        }
        o << "  [delay relative to chain 0; ? = could not tell]\n";
    }
    o << "  Per pair (data subcarriers): mean |H| [dB], phase slope [rad/subcarrier] (delay "
         "[ns])\n";
    for (unsigned tx = 0; tx < nTx; ++tx)
        for (unsigned rx = 0; rx < nRx; ++rx)
        {
            o << "    tx " << tx << " rx " << rx << ": ";
            if (!isPresent(tx, rx))
            {
                o << "MISSING\n";
                continue;
            }
            const auto s = summarize(*this, tx, rx);
            const double delay_ns = -s.phaseSlope_rad / (2 * M_PI * kSubcarrierSpacingHz) * 1e9;
            o << std::fixed << std::setprecision(1) << std::setw(7) << s.meanMagnitude_dB << " dB, "
              << std::setprecision(4) << std::setw(8) << s.phaseSlope_rad << " ("
              << std::setprecision(1) << delay_ns << " ns)\n";
        }
}

std::string CObservationWiFiCSI::exportTxtHeader() const
{
    // One row per frame: metadata, then re/im of every (tx, rx) pair over the data subcarriers
    // (pairs in tx-major order; missing pairs as NaN) so MATLAB/numpy load it as a matrix.
    std::ostringstream o;
    o << "%  SEQ  RSSI_DBM  CHANNEL  BW_MHZ  N_TX  N_RX  PRESENT_MASK  MAC_HI24  MAC_LO24  "
         "[RE IM] x (N_TX*N_RX*N_DATA_SUBCARRIERS: tx-major, then rx, then subcarrier k ascending)";
    return o.str();
}

std::string CObservationWiFiCSI::exportTxtDataRow() const
{
    std::ostringstream o;
    const uint64_t mac = transmitter.asUint64();
    o << sequenceNumber << " " << int(rssi_dBm) << " " << int(chanspec.centerChannel) << " "
      << chanspec.bandwidthMHz << " " << int(nTx) << " " << int(nRx) << " " << presentMask << " "
      << (mac >> 24) << " " << (mac & 0xFFFFFF);
    o << std::setprecision(7);
    const auto ks = dataSubcarriers();
    for (unsigned tx = 0; tx < nTx; ++tx)
        for (unsigned rx = 0; rx < nRx; ++rx)
        {
            const bool present = isPresent(tx, rx);
            const auto* p = pair(tx, rx);
            for (int k : ks)
            {
                if (!present)
                {
                    o << " NaN NaN";
                    continue;
                }
                const auto& h = p[subcarrierToBin(k, nfft())];
                o << " " << h.real() << " " << h.imag();
            }
        }
    return o.str();
}
