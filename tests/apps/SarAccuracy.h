/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once
// Synthetic-aperture bearings over random rooms (issue 18): each room is a sim::randomRoom
// (walls of random reflectivity, scatterers, furniture); its three access points are the
// static peers, each with one antenna; the moving robot stands still for 2 s, then drives a
// 1 m quarter circle (as the WSR dataset's robot) from a random start and heading, exchanging
// packets with every peer (sim::simulateExchanges: reciprocal multipath, per-exchange oscillator
// phase, detection delays, noise, int8, losses). Bearings from wifi-sar's chain (pairing by
// counter, products, estimate) with the true positions, or with a smooth position error of a
// given RMS (a tracking camera's), against the true azimuth from the start.
#include <mrpt/core/bits_math.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt_wifi/obs/bearing/BearingProcessor.h>
#include <mrpt_wifi/obs/bearing/SyntheticAperture.h>
#include <mrpt_wifi/sim/PacketExchange.h>
#include <mrpt_wifi/sim/RandomRoom.h>

#include <cmath>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace mrpt_wifi::sartest
{
struct PeerResult
{
    double error_deg = 0, std_deg = 0, quality = 0, range_m = 0;
    bool estimated = false;
};

struct RoomResult
{
    uint32_t seed = 0;
    double width = 0, height = 0;
    std::vector<PeerResult> peers;
};

/** The registered estimator `sar` in a BearingProcessor fed as csi-bearings feeds a rawlog
 *  with both recordings (each peer's under its own label) and odometry every 20 ms from t0
 *  (`odometryAt`: the robot's pose); the last bearing per peer. */
inline std::map<MacAddress, CObservationWiFiBearing::Ptr> lastChainBearings(
    const sim::ExchangeRecording& rec, const std::vector<sim::ExchangePeer>& peers,
    const std::function<mrpt::math::TPose2D(double)>& odometryAt, double t0,
    double positionStd_m = 0)
{
    bearing::BearingProcessor::Options po;
    for (size_t m = 0; m < peers.size(); ++m)
    {
        po.peerRecordings["PEER" + std::to_string(m)] = peers[m].mac;
        for (const auto& f : rec.heardByPeer[m]) f->sensorLabel = "PEER" + std::to_string(m);
    }
    mrpt::containers::yaml params = mrpt::containers::yaml::Map();
    params["position_std_m"] = positionStd_m;
    bearing::BearingProcessor proc(
        CsiPreprocessor(PreprocessOptions(), AntennaArray::singleElement()),
        bearing::createEstimator("sar", params), po);
    for (const auto& peer : rec.heardByPeer)
        for (const auto& f : peer) proc.process(*f);
    std::map<MacAddress, CObservationWiFiBearing::Ptr> last;
    double nextOdometry = t0;
    for (const auto& f : rec.heardByMover)
    {
        for (; nextOdometry <= mrpt::Clock::toDouble(f->timestamp) + 0.1; nextOdometry += 0.02)
            proc.addOdometry(mrpt::Clock::fromDouble(nextOdometry), odometryAt(nextOdometry));
        if (auto b = proc.process(*f)) last[f->transmitter] = b;
    }
    return last;
}

/** One room: `positionErrorRms_m` > 0 adds a smooth error to the positions the estimator sees.
 *  `viaBearingChain`: through the registered estimator `sar` in a BearingProcessor (both
 *  recordings and odometry fed as csi-bearings feeds a rawlog; the error of the last bearing,
 *  from the robot's pose at its frame) instead of wifi-sar's chain. */
inline RoomResult runRoom(
    uint32_t seed, const std::string& arraysDir, double positionErrorRms_m = 0,
    double positionStd_m = 0, bool viaBearingChain = false)
{
    sim::RandomRoomOptions ro;
    ro.arraysDir = arraysDir;
    const auto sc = sim::randomRoomScenario(seed, ro);
    const sim::ChannelModel channel(sc);
    RoomResult room;
    room.seed = seed;
    double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
    for (const auto& c : sc.roomCorners)
        x0 = std::min(x0, c.x), x1 = std::max(x1, c.x), y0 = std::min(y0, c.y),
        y1 = std::max(y1, c.y);
    room.width = x1 - x0, room.height = y1 - y0;
    mrpt::random::CRandomGenerator rng(seed * 7919u + 17u);
    // The arc: centre of the quarter circle 0.64 m to the side of the start.
    const double radius = 0.64, arcTime = 7.0, still = 2.0;
    const mrpt::math::TPoint2D start(
        rng.drawUniform(x0 + 1.2, x1 - 1.2), rng.drawUniform(y0 + 1.2, y1 - 1.2));
    const double heading = rng.drawUniform(-M_PI, M_PI);
    const double turn = rng.drawUniform(0, 1) < 0.5 ? 1.0 : -1.0;
    const mrpt::math::TPoint2D centre(
        start.x - turn * radius * std::sin(heading), start.y + turn * radius * std::cos(heading));
    const double t0 = sc.startTime_unix;
    const auto moverAt = [&](double t)
    {
        const double s = std::clamp((t - t0 - still) / arcTime, 0.0, 1.0) * M_PI / 2;
        const double a = heading - turn * M_PI / 2 + turn * s;
        return mrpt::math::TPoint2D(
            centre.x + radius * std::cos(a), centre.y + radius * std::sin(a));
    };
    // Smooth position error: two low-frequency sinusoids per axis, scaled to the RMS.
    const double p1 = rng.drawUniform(0, 2 * M_PI), p2 = rng.drawUniform(0, 2 * M_PI);
    const auto seenAt = [&](double t)
    {
        auto p = moverAt(t);
        const double u = (t - t0) / (still + arcTime);
        p.x += positionErrorRms_m * std::sqrt(2.0) * std::sin(2 * M_PI * 0.7 * u + p1);
        p.y += positionErrorRms_m * std::sqrt(2.0) * std::sin(2 * M_PI * 0.9 * u + p2);
        return p;
    };
    std::vector<sim::ExchangePeer> peers;
    for (const auto& tx : sc.transmitters) peers.push_back({tx.mac, {tx.pose.x, tx.pose.y}});
    const MacAddress moverMac = MacAddress::fromString("02:00:00:00:aa:01");
    sim::ExchangeOptions eo;
    const auto rec = sim::simulateExchanges(
        channel, moverAt, t0, t0 + still + arcTime, moverMac, peers, eo, seed);
    if (viaBearingChain)
    {
        constexpr double kHeading = 0.3;
        const auto last = lastChainBearings(
            rec, peers,
            [&](double t)
            {
                const auto p = seenAt(t);
                return mrpt::math::TPose2D(p.x, p.y, kHeading);
            },
            t0, positionStd_m);
        for (const auto& peer : peers)
        {
            PeerResult r;
            if (const auto it = last.find(peer.mac); it != last.end())
            {
                const auto s = moverAt(mrpt::Clock::toDouble(it->second->timestamp));
                const double truth = std::atan2(peer.position.y - s.y, peer.position.x - s.x);
                r.estimated = true;
                r.error_deg =
                    mrpt::RAD2DEG(std::remainder(it->second->aoa_rad + kHeading - truth, 2 * M_PI));
                r.std_deg = mrpt::RAD2DEG(it->second->aoaStd_rad);
                r.quality = it->second->quality;
                r.range_m = (peer.position - s).norm();
            }
            room.peers.push_back(r);
        }
        return room;
    }
    sar::SarOptions so;
    so.carrier_Hz = eo.chanspec.centerFrequencyHz();
    so.positionStd_m = positionStd_m;
    for (size_t m = 0; m < peers.size(); ++m)
    {
        std::vector<CObservationWiFiCSI::Ptr> mover;
        for (const auto& f : rec.heardByMover)
            if (f->transmitter == peers[m].mac) mover.push_back(f);
        std::vector<sar::Exchange> ex;
        for (const auto& pp : sar::pairedProducts(mover, rec.heardByPeer[m], 0, 0))
            ex.push_back({pp.time_s, seenAt(pp.time_s), pp.product});
        std::string why;
        PeerResult r;
        if (const auto est = sar::estimateBearing(ex, so, why))
        {
            // Truth from the true position at the estimate's start.
            const auto s = moverAt(est->startTime_s);
            const double truth = std::atan2(peers[m].position.y - s.y, peers[m].position.x - s.x);
            r.estimated = true;
            r.error_deg = mrpt::RAD2DEG(std::remainder(est->azimuth_rad - truth, 2 * M_PI));
            r.std_deg = mrpt::RAD2DEG(est->azimuthStd_rad);
            r.quality = est->quality;
            r.range_m = (peers[m].position - s).norm();
        }
        room.peers.push_back(r);
    }
    return room;
}
}  // namespace mrpt_wifi::sartest
