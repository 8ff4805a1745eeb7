/* mrpt_wifi — test helper: closed-form multipath CSI, independent of the simulator. */
#pragma once

#include <mrpt_wifi/obs/AntennaArray.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <complex>
#include <random>
#include <vector>

namespace mrpt_wifi::test
{
struct SyntheticPath
{
    double aoa_rad = 0;
    double aod_rad = 0;
    double delay_s = 20e-9;
    std::complex<double> gain{1, 0};
};

struct SyntheticSpec
{
    Chanspec chanspec = Chanspec::make(155, 80);
    AntennaArray rx;
    AntennaArray tx = AntennaArray::singleElement();
    unsigned streams = 1;
    std::vector<SyntheticPath> paths;
    double snr_dB = 200;                 //!< per element and subcarrier; 200: no noise
    double sto_s = 0;                    //!< sampling-time offset (phase −2π k Δf sto)
    bool signFlip80 = true;              //!< negate k = −128..−65 as the RT-AC86U firmware does
    std::vector<double> rxPhaseOffsets;  //!< per antenna, constant over k
    uint32_t seed = 1;
    MacAddress mac = MacAddress::fromString("02:00:00:00:00:01");
};

/** H[m][i][k] = Σ_p g_p e^{−j2π f_k τ_p} e^{+j2π f_k/c a_i·u(θ_p)} e^{+j2π f_k/c b_m·u(φ_p)}
 *  · e^{jψ_i} · e^{−j2π k Δf sto} + noise, on all occupied subcarriers |k| ≤ edge. */
inline CObservationWiFiCSI synthesize(const SyntheticSpec& s)
{
    CObservationWiFiCSI o;
    o.chanspec = s.chanspec;
    o.transmitter = s.mac;
    o.rssi_dBm = -50;
    o.timestamp = mrpt::Clock::fromDouble(1700000000.0);
    const unsigned nfft = s.chanspec.nfft(), nRx = unsigned(s.rx.size());
    o.resize(s.streams, nRx, nfft);
    const int edge = s.chanspec.bandwidthMHz == 80 ? 122 : s.chanspec.bandwidthMHz == 40 ? 58 : 28;
    std::mt19937 rng(s.seed);
    double power = 0;
    for (const auto& p : s.paths) power += std::norm(p.gain);
    const double sigma = std::sqrt(power / std::pow(10.0, s.snr_dB / 10) / 2);
    std::normal_distribution<double> n01(0, 1);
    for (unsigned m = 0; m < s.streams; ++m)
        for (unsigned i = 0; i < nRx; ++i)
        {
            o.setPresent(m, i);
            for (int k = -edge; k <= edge; ++k)
            {
                const double f = subcarrierFrequencyHz(s.chanspec, k);
                std::complex<double> h = 0;
                for (const auto& p : s.paths)
                    h += p.gain *
                         std::polar(
                             1.0, -2 * M_PI * f * p.delay_s + s.rx.steeringPhase(i, p.aoa_rad, f) +
                                      s.tx.steeringPhase(m, p.aod_rad, f));
                if (!s.rxPhaseOffsets.empty()) h *= std::polar(1.0, s.rxPhaseOffsets[i]);
                h *= std::polar(1.0, -2 * M_PI * k * kSubcarrierSpacingHz * s.sto_s);
                if (s.snr_dB < 150) h += std::complex<double>(sigma * n01(rng), sigma * n01(rng));
                if (s.signFlip80 && s.chanspec.bandwidthMHz == 80 && k < -64) h = -h;
                o.at(m, i, subcarrierToBin(k, nfft)) = std::complex<float>(h);
            }
        }
    return o;
}

inline AntennaArray loadArray(const std::string& name)
{
    return AntennaArray::fromYamlFile(
        std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays/" + name + ".yaml");
}

}  // namespace mrpt_wifi::test
