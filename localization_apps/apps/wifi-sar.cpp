/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * wifi-sar: bearings from one antenna on a moving robot to peers it exchanges packets with (the
 * WSR Toolbox's synthetic aperture): the CSI the moving robot recorded (--rx), what each peer
 * recorded of the robot's packets (--tx), and the robot's trajectory. One bearing per peer. */
#include <mrpt/3rdparty/tclap/CmdLine.h>
#include <mrpt/core/bits_math.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/DeviceMapper.h>
#include <mrpt_wifi/localization/Plot.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/localization/Trajectory2D.h>
#include <mrpt_wifi/localization/TransmitterMap.h>
#include <mrpt_wifi/obs/CommandLine.h>
#include <mrpt_wifi/obs/bearing/SyntheticAperture.h>
#include <mrpt_wifi/sensor/CsiDecoder.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <unordered_map>

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;

namespace
{
std::vector<CObservationWiFiCSI::Ptr> decodeFrames(
    const std::string& path, const CsiDecodeOptions& options, bool quiet)
{
    std::vector<CObservationWiFiCSI::Ptr> frames;
    CsiDecodeSummary summary;
    cli::Progress progress("reading " + path, !quiet);
    decodeCsiFile(
        path, "auto", options, [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(f); },
        [&](double x) { progress.update(x); }, &summary);
    if (!quiet) progress.done(std::to_string(frames.size()) + " frames");
    if (!summary.rejected.empty())
        std::cerr << "wifi-sar: " << path << ": " << summary.asString() << "\n";
    return frames;
}

/** DIR/MAC-profile.png (the far-field profile, estimate and truth) and DIR/MAC-aperture.png
 *  (the path of the exchanges and the bearing); `trueAz` NaN when unknown. */
void writeProfilePictures(
    const std::string& dir, const MacAddress& mac, const std::string& file,
    const sar::SarEstimate& est, double trueAz, const std::vector<sar::Exchange>& exchanges)
{
    namespace plot = localization::plot;
    std::string name = dir + "/" + mac.asString();
    std::replace(name.begin() + long(dir.size()), name.end(), ':', '-');
    const auto line = [](const std::string& title, std::vector<double> x, std::vector<double> y,
                         const char* style) {
        return plot::Series{title, x, y, style};
    };
    const char* estimateStyle = "lines lw 2 lc rgb 'red'";
    const char* truthStyle = "lines lw 2 dt 2 lc rgb 'black'";

    plot::Figure prof;
    prof.title = mac.asString() + " (" + mrpt::system::extractFileName(file) +
                 "): Bartlett profile of the synthetic aperture";
    prof.xlabel = "azimuth in the trajectory's frame [deg]";
    prof.ylabel = "power / peak";
    plot::Series ps{"far-field profile", {}, {}};
    const double step = 360.0 / double(est.profile.size());
    for (size_t a = 0; a < est.profile.size(); ++a)
        ps.x.push_back(-180.0 + double(a) * step), ps.y.push_back(est.profile[a]);
    prof.series.push_back(ps);
    const double estDeg = mrpt::RAD2DEG(est.azimuth_rad), trueDeg = mrpt::RAD2DEG(trueAz);
    prof.series.push_back(line("estimate", {estDeg, estDeg}, {0.0, 1.05}, estimateStyle));
    if (!std::isnan(trueAz))
        prof.series.push_back(line("truth", {trueDeg, trueDeg}, {0.0, 1.05}, truthStyle));

    plot::Figure ap;
    ap.title = mac.asString() + ": path of the used exchanges and the bearing";
    ap.xlabel = "x [m]", ap.ylabel = "y [m]", ap.equalAxes = true;
    plot::Series path{"path", {}, {}};
    for (const auto& e : exchanges) path.x.push_back(e.position.x), path.y.push_back(e.position.y);
    ap.series.push_back(path);
    const auto ray = [&](const std::string& title, double az, const char* style)
    {
        constexpr double kLength_m = 2.0;
        return line(
            title, {est.start.x, est.start.x + kLength_m * std::cos(az)},
            {est.start.y, est.start.y + kLength_m * std::sin(az)}, style);
    };
    ap.series.push_back(ray("bearing", est.azimuth_rad, estimateStyle));
    if (!std::isnan(trueAz)) ap.series.push_back(ray("truth", trueAz, truthStyle));

    mrpt::system::createDirectory(dir);
    std::string why;
    if (!plot::savePng(prof, name + "-profile.png", &why) ||
        !plot::savePng(ap, name + "-aperture.png", &why))
        std::cerr << "wifi-sar: no profile pictures: " << why << "\n";
}

}  // namespace

int main(int argc, char** argv)
{
    return cli::runMain(
        "wifi-sar",
        [&]
        {
            TCLAP::CmdLine cmd(
                "Bearings from one antenna on a moving robot to the peers it exchanges packets "
                "with (WSR Toolbox's synthetic aperture): forward x reverse channel of each "
                "exchange, paired by the sender's frame counter, over the robot's trajectory.",
                ' ', "0.1");
            TCLAP::ValueArg<std::string> argRx(
                "", "rx", "CSI the moving robot recorded of its peers (WSR .dat or rawlog)", true,
                "", "CSI_RX.dat", cmd);
            TCLAP::MultiArg<std::string> argTx(
                "", "tx",
                "CSI one peer recorded of the moving robot's packets; FILE@MAC names the peer's "
                "MAC (else the sender in --rx whose channel matches, by reciprocity)",
                true, "CSI_TX.dat[@MAC]", cmd);
            TCLAP::ValueArg<std::string> argTraj(
                "", "trajectory",
                "The moving robot's trajectory on its CSI clock: TUM, the WSR dataset's CSV "
                "(motion capture, odometry or tracking camera), or a rawlog's odometry",
                true, "", "FILE", cmd);
            TCLAP::ValueArg<std::string> argAlign(
                "", "align-to",
                "Express the bearings in this trajectory's frame: --trajectory is rigidly "
                "aligned to it over the exchanges (e.g. odometry or T265 onto motion capture)",
                false, "", "FILE", cmd);
            TCLAP::ValueArg<std::string> argTruth(
                "", "truth",
                "Peers' true positions (TransmitterMap YAML, by MAC): adds the true azimuth and "
                "the error to the output",
                false, "", "PEERS.yaml", cmd);
            TCLAP::ValueArg<std::string> argLocate(
                "", "locate",
                "Known peer positions (TransmitterMap YAML, by MAC): also locate the moving robot "
                "at its start from its bearings (the device mapper's robust triangulation; WSR's "
                "localization)",
                false, "", "PEERS.yaml", cmd);
            TCLAP::ValueArg<std::string> argAntennaOffset(
                "", "antenna-offset",
                "Where the antenna is in the trajectory's body frame, 'x y' [m] (a tracking "
                "camera mounted away from the antenna); needs the trajectory's heading",
                false, "0 0", "x y", cmd);
            TCLAP::ValueArg<double> argPositionStd(
                "", "position-std",
                "RMS error of the trajectory's positions over the drive [m]: motion capture 0 "
                "(default), a tracking camera about 0.02, wheel odometry more; widens sigma",
                false, 0.0, "M", cmd);
            TCLAP::ValueArg<std::string> argChannel(
                "", "channel", "Channel of the exchanges, CH or CH/BW (WSR dataset: 108)", false,
                "108", "CH", cmd);
            TCLAP::ValueArg<unsigned> argRxChain(
                "", "rx-chain", "Receive chain of the moving robot's single antenna", false, 0, "N",
                cmd);
            TCLAP::ValueArg<unsigned> argPeerChain(
                "", "peer-chain", "Receive chain of the peers' antenna", false, 0, "N", cmd);
            TCLAP::ValueArg<double> argTimeOffset(
                "", "time-offset",
                "Added to CSI times before looking up the trajectory (pose latency) [s]", false,
                0.0, "S", cmd);
            TCLAP::ValueArg<std::string> argRawlogOut(
                "", "rawlog",
                "Write the bearings as CObservationWiFiBearing (AoA at the start, in the robot's "
                "frame) with the trajectory as odometry, for wifi-pf-localization / "
                "pf-localization",
                false, "", "OUT.rawlog", cmd);
            TCLAP::ValueArg<std::string> argProfiles(
                "", "profiles",
                "Write per peer DIR/MAC-profile.png (the azimuth profile, estimate and truth) and "
                "DIR/MAC-aperture.png (the path used and the bearing); needs gnuplot",
                false, "", "DIR", cmd);
            TCLAP::ValueArg<std::string> argCsv(
                "", "csv", "Write one row per peer", false, "", "OUT.csv", cmd);
            TCLAP::ValueArg<std::string> argExchanges(
                "", "exchanges",
                "Write every exchange placed on the trajectory, one row each (mac, time, antenna "
                "x y, product re im): the estimator's input, to replay or plot",
                false, "", "OUT.csv", cmd);
            TCLAP::SwitchArg argQuiet("q", "quiet", "No progress", cmd);
            // `--antenna-offset -0.2 -0.08` as documented, or quoted as one token.
            cli::JoinedArgv args(argc, argv, "--antenna-offset", 2);
            if (const int rc = cli::parseCommandLine(cmd, args.argc(), args.argv()); rc >= 0)
                return rc;
            const bool quiet = argQuiet.getValue();

            CsiDecodeOptions decode;
            decode.chanspec = Chanspec::fromString(argChannel.getValue());
            const auto readTrajectory = [](const std::string& path)
            {
                const bool rawlog =
                    path.size() >= 7 && path.compare(path.size() - 7, 7, ".rawlog") == 0;
                if (!rawlog) return Trajectory2D::fromFile(path);
                auto odo = readRawlog(path).odometry;
                if (odo.empty()) throw std::runtime_error("'" + path + "' holds no odometry");
                return odo;
            };
            Trajectory2D traj = readTrajectory(argTraj.getValue());
            {
                std::istringstream is(argAntennaOffset.getValue());
                mrpt::math::TPoint2D offset;
                if (!(is >> offset.x >> offset.y))
                    throw std::invalid_argument(
                        "--antenna-offset: expected 'x y' in metres, got '" +
                        argAntennaOffset.getValue() + "'");
                for (auto& p : traj.poses)
                {
                    const auto antenna = mrpt::poses::CPose2D(p).composePoint(offset);
                    p.x = antenna.x, p.y = antenna.y;
                }
            }
            std::optional<TransmitterMap> truth;
            if (argTruth.isSet()) truth = TransmitterMap::fromYamlFile(argTruth.getValue());

            const auto rxFrames = decodeFrames(argRx.getValue(), decode, quiet);
            std::unordered_map<MacAddress, std::vector<CObservationWiFiCSI::Ptr>> bySender;
            for (const auto& f : rxFrames) bySender[f->transmitter].push_back(f);
            if (bySender.empty())
                throw std::runtime_error("'" + argRx.getValue() + "' holds no CSI frames");

            // Which sender each --tx file belongs to, and its exchanges.
            struct Peer
            {
                std::string file;
                MacAddress mac;
                std::vector<sar::PairedProduct> products;
                std::vector<sar::Exchange> exchanges;  // the products placed on the trajectory
                size_t pairs = 0;
                double carrier_Hz = 0;  // the channel of the exchanges used
            };
            std::vector<Peer> peers;
            for (const auto& spec : argTx.getValue())
            {
                Peer peer;
                const auto at = spec.rfind('@');
                peer.file = at == std::string::npos ? spec : spec.substr(0, at);
                const auto txFrames = decodeFrames(peer.file, decode, quiet);
                if (at != std::string::npos)
                {
                    peer.mac = MacAddress::fromString(spec.substr(at + 1));
                    if (!bySender.count(peer.mac))
                        throw std::runtime_error(
                            "--tx " + spec + ": no frame from " + peer.mac.asString() + " in '" +
                            argRx.getValue() + "'");
                }
                else
                {
                    double best = -2, second = -2;
                    for (const auto& [mac, frames] : bySender)
                    {
                        const double score = sar::reciprocityScore(
                            frames, txFrames, argRxChain.getValue(), argPeerChain.getValue());
                        if (score > best)
                            second = best, best = score, peer.mac = mac;
                        else
                            second = std::max(second, score);
                    }
                    std::cout << peer.file << ": sender " << peer.mac.asString()
                              << " (amplitude correlation " << best << ", next " << second << ")\n";
                    if (best < 0.5 || best - second < 0.2)
                        throw std::runtime_error(
                            "--tx " + peer.file +
                            ": cannot tell which sender it recorded (reciprocity " +
                            std::to_string(best) + " vs " + std::to_string(second) +
                            "); name it as FILE@MAC");
                }
                // A robot that hops channels hears a peer on several carriers, and an aperture
                // is coherent on one: the channel with the most frames from the peer is used.
                std::map<double, std::vector<CObservationWiFiCSI::Ptr>> byCarrier;
                for (const auto& f : bySender[peer.mac])
                    byCarrier[f->chanspec.centerFrequencyHz()].push_back(f);
                const auto most = std::max_element(
                    byCarrier.begin(), byCarrier.end(),
                    [](const auto& a, const auto& b) { return a.second.size() < b.second.size(); });
                peer.carrier_Hz = most->first;
                if (byCarrier.size() > 1 && !quiet)
                {
                    std::cout << peer.mac.asString() << ": heard on " << byCarrier.size()
                              << " channels; using " << most->second.front()->chanspec.asString()
                              << " (" << most->second.size() << " of " << bySender[peer.mac].size()
                              << " frames)\n";
                }
                peer.products = sar::pairedProducts(
                    most->second, txFrames, argRxChain.getValue(), argPeerChain.getValue(),
                    &peer.pairs);
                peers.push_back(std::move(peer));
            }

            // Frame of the output: the trajectory's own, or the reference it is rigidly aligned
            // to over the span of the exchanges (both on their own clocks).
            if (argAlign.isSet())
            {
                const auto ref = readTrajectory(argAlign.getValue());
                double t0 = HUGE_VAL, t1 = -HUGE_VAL;
                for (const auto& peer : peers)
                    for (const auto& pp : peer.products)
                        t0 = std::min(t0, pp.time_s), t1 = std::max(t1, pp.time_s);
                std::vector<mrpt::math::TPoint2D> a, b;
                for (size_t i = 0; i < traj.size(); ++i)
                {
                    mrpt::math::TPose2D r;
                    if (traj.t[i] >= t0 && traj.t[i] <= t1 && ref.interpolate(traj.t[i], r, 0.5))
                        a.push_back({traj.poses[i].x, traj.poses[i].y}), b.push_back({r.x, r.y});
                }
                if (a.size() < 3)
                    throw std::runtime_error(
                        "--align-to: fewer than 3 poses of both trajectories during the exchanges");
                const mrpt::poses::CPose2D toRef(alignRigid2D(a, b));
                for (auto& pose : traj.poses) pose = (toRef + mrpt::poses::CPose2D(pose)).asTPose();
            }

            sar::SarOptions options;
            options.positionStd_m = argPositionStd.getValue();
            // A search for the offset that maximises the peers' coherence was tried: on the
            // development recordings coherence hardly changes with the offset (the bearing
            // absorbs it), so the offset it picks made errors worse; the offset is an input.
            const double offset = argTimeOffset.getValue();
            for (auto& peer : peers)
                for (const auto& pp : peer.products)
                {
                    mrpt::math::TPose2D pose;
                    if (traj.interpolate(pp.time_s + offset, pose, 0.5))
                        peer.exchanges.push_back({pp.time_s, {pose.x, pose.y}, pp.product});
                }

            if (argExchanges.isSet())
            {
                std::ofstream out(argExchanges.getValue());
                if (!out)
                    throw std::runtime_error("cannot write '" + argExchanges.getValue() + "'");
                out << "mac,time,x,y,re,im\n";
                char row[256];
                for (const auto& peer : peers)
                    for (const auto& e : peer.exchanges)
                    {
                        std::snprintf(
                            row, sizeof(row), "%s,%.6f,%.6f,%.6f,%.9g,%.9g\n",
                            peer.mac.asString().c_str(), e.time_s, e.position.x, e.position.y,
                            e.product.real(), e.product.imag());
                        out << row;
                    }
            }
            std::ofstream csv;
            if (argCsv.isSet())
            {
                csv.open(argCsv.getValue());
                if (!csv) throw std::runtime_error("cannot write '" + argCsv.getValue() + "'");
                csv << "mac,file,azimuth_deg,azimuth_std_deg,quality,packets_used,start_x,"
                       "start_y,start_time,aperture_m,range_m,pairs,true_azimuth_deg,error_deg,"
                       "coherence,time_offset,mirror_azimuth_deg,mirror_power,strong_peaks,"
                       "direction_std_deg,"
                       "alternative_azimuth_deg,alternative_weight\n";
            }
            int failed = 0;
            std::vector<BearingRay> toKnownPeers;
            std::optional<mrpt::math::TPoint2D> start;  // of the first peer with a bearing
            std::vector<BearingRecord> records;
            const auto knownPeers =
                argLocate.isSet()
                    ? std::optional(TransmitterMap::fromYamlFile(argLocate.getValue()))
                    : std::nullopt;
            for (const auto& peer : peers)
            {
                std::string whyNot;
                // The channel the frames say (a rawlog's), else --channel's (.dat records have
                // none).
                options.carrier_Hz = peer.carrier_Hz;
                const auto est = sar::estimateBearing(peer.exchanges, options, whyNot);
                if (!est)
                {
                    if (peer.exchanges.size() < peer.products.size() / 2 && !traj.empty())
                        whyNot += "; only " + std::to_string(peer.exchanges.size()) + " of " +
                                  std::to_string(peer.products.size()) +
                                  " exchanges fall inside the trajectory's time span (" +
                                  std::to_string(traj.t.front()) + " to " +
                                  std::to_string(traj.t.back()) +
                                  "): check its clock or --time-offset";
                    std::cout << peer.mac.asString() << " (" << peer.file
                              << "): no bearing: " << whyNot << "\n";
                    ++failed;
                    continue;
                }
                {
                    // AoA in the robot's frame at the start (heading from the trajectory).
                    mrpt::math::TPose2D at;
                    traj.interpolate(est->startTime_s + offset, at, 0.5);
                    BearingRecord r;
                    r.t = est->startTime_s;  // CSI clock, as the odometry written below
                    r.transmitter = peer.mac;
                    r.hasAoa = true;
                    r.aoa = std::remainder(est->azimuth_rad - at.phi, 2 * M_PI);
                    r.aoaStd = est->azimuthStd_rad;
                    // A path too straight to tell the peer from its mirror image: both.
                    if (est->mirrorPower >= sar::SyntheticApertureEstimator::kMirrorAmbiguity)
                    {
                        r.aoaAmbiguous = true;
                        r.aoaMirror = std::remainder(est->mirror_rad - at.phi, 2 * M_PI);
                    }
                    // The profile's other strong peaks, with the weights measured on the
                    // development sets (SarPeak::weight).
                    r.aoaDirectionStd = est->azimuthStd_rad;
                    for (size_t i = 1; i < est->peaks.size(); ++i)
                    {
                        const auto& peak = est->peaks[i];
                        if (peak.weight <= 0) continue;
                        const double aoa = std::remainder(peak.azimuth_rad - at.phi, 2 * M_PI);
                        if (!r.hasAoaAlternative)
                        {
                            r.hasAoaAlternative = true;
                            r.aoaAlternative = aoa, r.aoaAlternativeWeight = peak.weight;
                            r.aoaDirectionStd = est->lobeStd_rad;
                        }
                        else
                            r.moreAoaAlternatives.push_back({aoa, peak.weight});
                    }
                    records.push_back(r);
                }
                if (!start) start = est->start;
                if (knownPeers)
                    if (const auto* k = knownPeers->find(peer.mac))
                    {
                        // A ray cast back from the peer; a strong second peak (weight ≥ 0.2)
                        // enters as the ray's other candidate (the device mapper's mixture),
                        // each with the σ of a single peak: on the WSR development sets this
                        // located NLOS_Set_A's receiver to 0.84 m median, p90 1.92 m
                        // (2.54 m with one direction and the wider σ).
                        localization::BearingRay ray;
                        ray.x = k->pose.x, ray.y = k->pose.y;
                        ray.aoa = mrpt::math::wrapToPi(est->azimuth_rad + M_PI);
                        ray.sigma = est->azimuthStd_rad;
                        if (est->peaks.size() > 1 && est->peaks[1].weight >= 0.2)
                        {
                            ray.ambiguous = true;
                            ray.mirror = mrpt::math::wrapToPi(est->peaks[1].azimuth_rad + M_PI);
                            ray.sigma = std::max(
                                est->lobeStd_rad, est->azimuthStd_rad * options.onePeakStd_deg /
                                                      options.severalPeaksStd_deg);
                        }
                        toKnownPeers.push_back(ray);
                    }
                double trueAz = std::nan(""), err = std::nan("");
                if (truth)
                    if (const auto* k = truth->find(peer.mac))
                    {
                        trueAz = std::atan2(k->pose.y - est->start.y, k->pose.x - est->start.x);
                        err = std::remainder(est->azimuth_rad - trueAz, 2 * M_PI);
                    }
                if (argProfiles.isSet())
                    writeProfilePictures(
                        argProfiles.getValue(), peer.mac, peer.file, *est, trueAz, peer.exchanges);
                char line[512];
                std::snprintf(
                    line, sizeof(line),
                    "%s azimuth %7.2f deg  sigma %5.2f  quality %.2f  packets %zu of %zu  "
                    "aperture %.2f m  start (%.3f, %.3f)%s",
                    peer.mac.asString().c_str(), mrpt::RAD2DEG(est->azimuth_rad),
                    mrpt::RAD2DEG(est->azimuthStd_rad), est->quality, est->packetsUsed, peer.pairs,
                    est->apertureLength_m, est->start.x, est->start.y,
                    std::isnan(err)
                        ? ""
                        : ("  error " + std::to_string(mrpt::RAD2DEG(err)) + " deg").c_str());
                std::cout << line << "\n";
                if (csv.is_open())
                {
                    std::snprintf(
                        line, sizeof(line),
                        "%s,%s,%.3f,%.3f,%.4f,%zu,%.4f,%.4f,%.6f,%.3f,%.2f,%zu,%.3f,%.3f,%.4f,%."
                        "3f,%.3f,%.4f,%zu,%.3f,%.3f,%.2f\n",
                        peer.mac.asString().c_str(), peer.file.c_str(),
                        mrpt::RAD2DEG(est->azimuth_rad), mrpt::RAD2DEG(est->azimuthStd_rad),
                        est->quality, est->packetsUsed, est->start.x, est->start.y,
                        est->startTime_s, est->apertureLength_m, est->range_m, peer.pairs,
                        mrpt::RAD2DEG(trueAz), mrpt::RAD2DEG(err), est->coherence, offset,
                        mrpt::RAD2DEG(est->mirror_rad), est->mirrorPower, est->peaks.size(),
                        mrpt::RAD2DEG(est->lobeStd_rad),
                        est->peaks.size() > 1 ? mrpt::RAD2DEG(est->peaks[1].azimuth_rad)
                                              : std::nan(""),
                        est->peaks.size() > 1 ? est->peaks[1].weight : 0.0);
                    csv << line;
                }
            }
            if (knownPeers)
            {
                // The bearings are taken from each peer's own start; they differ by the packets
                // dropped at the start, by millimetres.
                DeviceMapOptions locateOptions;
                locateOptions.minRays = 2;  // as locateObserver
                const auto p = triangulateDevice(toKnownPeers, locateOptions);
                if (!p.localized)
                    std::cout << "not located: " << p.note << "\n";
                else
                    std::printf(
                        "located: (%.3f, %.3f), %.3f m from the trajectory's start (%.3f, %.3f); "
                        "1-sigma %.3f m\n",
                        p.x, p.y, std::hypot(p.x - start->x, p.y - start->y), start->x, start->y,
                        std::sqrt(0.5 * (p.cov[0] + p.cov[2])));
            }
            if (argRawlogOut.isSet())
            {
                std::sort(
                    records.begin(), records.end(),
                    [](const auto& a, const auto& b) { return a.t < b.t; });
                // The trajectory, shifted to the CSI clock, is the odometry.
                Trajectory2D odo;
                for (size_t i = 0; i < traj.size(); ++i)
                    odo.push_back(traj.t[i] - offset, traj.poses[i]);
                const size_t n = writePfRawlog(argRawlogOut.getValue(), records, odo);
                std::cout << "wrote " << n << " observations to " << argRawlogOut.getValue()
                          << "\n";
            }
            std::cout << "wifi-sar: " << peers.size() - size_t(failed) << " of " << peers.size()
                      << " peers with a bearing\n";
            // As wifi-calibrate: 2 = it ran, but part of the result could not be determined;
            // no peer with a bearing is no result at all, an error (1).
            if (failed == 0) return 0;
            return size_t(failed) == peers.size() ? 1 : 2;
        });
}
