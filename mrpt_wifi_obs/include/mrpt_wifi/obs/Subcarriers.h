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
 *  20 MHz: −28..28 minus {0, ±7, ±21} → 52;
 *  160 MHz (VHT, two 80 MHz segments at ∓128): |k| in 6..126 and 130..250 minus the pilots
 *  ±25, ±53, ±89, ±117, ±139, ±167, ±203, ±231 → 468.
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

/** Whether subcarrier k lies in a 20 MHz sub-band the Nexmon 4366c0 firmware reports with its
 *  sign inverted (DESIGN.md §4): at 80 MHz the lowest one, k = −128..−65 (verified on real
 *  captures); at 160 MHz the lowest 20 MHz of each 80 MHz segment, k = −256..−193 and 0..63 —
 *  the 80 MHz behaviour per segment, an extrapolation not verified on hardware. */
bool inNegatedSubband(int k, unsigned bandwidthMHz);

/** The 802.11n grouped subcarriers (beamforming feedback, Ng = 2 at 20 MHz, Ng = 4 at 40 MHz;
 *  30 each) that the Intel 5300 CSI Tool reports. Throws std::invalid_argument otherwise. */
const std::vector<int>& htGroupedSubcarriers(unsigned bandwidthMHz);

}  // namespace mrpt_wifi
