/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt/math/TPoint2D.h>
#include <mrpt_wifi/obs/CObservationWiFiCSI.h>
#include <mrpt_wifi/obs/MacAddress.h>
#include <mrpt_wifi/sim/ChannelModel.h>

#include <cstdint>
#include <functional>
#include <vector>

/** Two-robot packet exchanges, as the WSR Toolbox records them (issue 18): a moving robot with
 * one antenna and static peers with one antenna each take turns; each side's Intel 5300-style
 * receiver reports the channel of the other's packet. The propagation (multipath of the room) is
 * reciprocal; the impairments are not: each exchange has its own oscillator phase, which enters
 * the two directions with opposite signs (plus a residual from the turnaround time), each
 * reception its own detection delay, noise and int8 quantisation, and packets are lost in either
 * direction independently. */
namespace mrpt_wifi::sim
{
struct ExchangeOptions
{
    Chanspec chanspec = Chanspec::make(108, 20);  //!< the WSR dataset's channel
    double rate_Hz = 120;                         //!< exchanges per second with each peer
    double lossProbability = 0.05;                //!< per direction
    double snr_dB = 25;                           //!< per subcarrier, before quantisation
    double maxDetectionDelay_s = 100e-9;          //!< per reception, uniform in [0, max)
    /** Residual of the oscillator phase between a packet and its reply (the phase drifts during
     *  the turnaround): Gaussian σ [rad]. */
    double turnaroundPhaseStd_rad = 0.3;
    double peerClockOffset_s = 39.0;  //!< peers' clocks differ (pairing is by counter)
};

struct ExchangePeer
{
    MacAddress mac;
    mrpt::math::TPoint2D position;
};

struct ExchangeRecording
{
    /** What the moving robot recorded: every peer's packets (transmitter = the peer). */
    std::vector<CObservationWiFiCSI::Ptr> heardByMover;
    /** What each peer recorded of the robot's packets (transmitter = the robot), per peer. */
    std::vector<std::vector<CObservationWiFiCSI::Ptr>> heardByPeer;
};

/** Exchanges with every peer between t0 and t1 (seconds on the robot's clock, UNIX time), the
 * robot's antenna at `moverAt(t)`. Frames carry the 30 grouped subcarriers as the Intel 5300
 * reports them, firmwareCounter = the sender's frame counter. Deterministic in `seed`. */
ExchangeRecording simulateExchanges(
    const ChannelModel& channel, const std::function<mrpt::math::TPoint2D(double)>& moverAt,
    double t0, double t1, const MacAddress& moverMac, const std::vector<ExchangePeer>& peers,
    const ExchangeOptions& options, uint32_t seed);

}  // namespace mrpt_wifi::sim
