/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/obs/Chanspec.h>

#include <vector>

namespace mrpt_wifi
{
/** 802.11 OFDM subcarrier spacing. */
constexpr double kSubcarrierSpacingHz = 312.5e3;

/** Data subcarrier indices k (ascending) as WiROS uses them:
 *  80 MHz: −122..122 minus {0, ±1, ±11, ±39, ±75, ±103} → 234;
 *  40 MHz: −58..58 minus {0, ±1, ±11, ±25, ±53} → 108;
 *  20 MHz: −28..28 minus {0, ±7, ±21} → 52.
 *  Throws std::invalid_argument for another bandwidth. */
const std::vector<int>& dataSubcarriers(unsigned bandwidthMHz);

/** Bin index in subcarrier order (after fftshift) of subcarrier k: k + N/2. */
inline unsigned subcarrierToBin(int k, unsigned nfft)
{
    return static_cast<unsigned>(k + int(nfft / 2));
}
/** Subcarrier index k of a bin in subcarrier order. */
inline int binToSubcarrier(unsigned bin, unsigned nfft)
{
    return int(bin) - int(nfft / 2);
}

/** Frequency of subcarrier k: f_c + k · 312.5 kHz. */
inline double subcarrierFrequencyHz(const Chanspec& cs, int k)
{
    return cs.centerFrequencyHz() + k * kSubcarrierSpacingHz;
}

/** Subcarrier indices (in subcarrier order) whose raw words the current Nexmon firmware
 *  overwrites with PHY status: raw words 0–2 (k = 0, +1, +2) at 40/80 MHz, 28–30 at 20 MHz. */
std::vector<int> firmwareOverwrittenSubcarriers(unsigned bandwidthMHz);

}  // namespace mrpt_wifi
