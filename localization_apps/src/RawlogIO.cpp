/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/RawlogIO.h>
#include <mrpt_wifi/obs/RawlogReader.h>

#include <algorithm>
#include <stdexcept>

namespace mrpt_wifi::localization
{
BearingRecord recordFromObservation(const CObservationWiFiBearing& o)
{
    BearingRecord r;
    r.t = mrpt::Clock::toDouble(o.timestamp);
    r.transmitter = o.transmitter;
    r.sensorPose = mrpt::math::TPose2D(o.sensorPose.x(), o.sensorPose.y(), o.sensorPose.yaw());
    r.hasAoa = true;
    r.aoa = o.aoa_rad, r.aoaStd = o.aoaStd_rad;
    r.aoaAmbiguous = o.aoaAmbiguous, r.aoaMirror = o.aoaMirror_rad;
    r.hasAoaAlternative = o.hasAoaAlternative;
    r.aoaAlternative = o.aoaAlternative_rad, r.aoaAlternativeWeight = o.aoaAlternativeWeight;
    r.aoaDirectionStd = o.hasAoaAlternative ? o.aoaDirectionStd_rad : o.aoaStd_rad;
    if (o.hasAoaAlternative)
        for (const auto& a : o.moreAoaAlternatives)
            r.moreAoaAlternatives.push_back({a.aoa_rad, a.weight});
    r.hasAod = o.hasAod;
    r.aod = o.aod_rad, r.aodStd = o.aodStd_rad;
    r.aodAmbiguous = o.aodAmbiguous, r.aodMirror = o.aodMirror_rad;
    return r;
}

CObservationWiFiBearing::Ptr observationFromRecord(const BearingRecord& r, const std::string& alg)
{
    auto o = CObservationWiFiBearing::Create();
    o->timestamp = mrpt::Clock::fromDouble(r.t);
    o->sensorLabel = "WIFI_BEARING";
    o->sensorPose = mrpt::poses::CPose3D(r.sensorPose.x, r.sensorPose.y, 0, r.sensorPose.phi, 0, 0);
    o->transmitter = r.transmitter;
    o->chanspec = Chanspec::make(155, 80);
    o->algorithm = alg;
    o->framesUsed = 1;
    // An AoD-only record still needs an AoA field: mark it unusable with a huge σ.
    o->aoa_rad = r.hasAoa ? r.aoa : 0;
    o->aoaStd_rad = r.hasAoa ? r.aoaStd : 1e3;
    o->aoaAmbiguous = r.hasAoa && r.aoaAmbiguous;
    o->aoaMirror_rad = r.aoaMirror;
    o->hasAoaAlternative = r.hasAoa && r.hasAoaAlternative;
    o->aoaAlternative_rad = r.aoaAlternative, o->aoaAlternativeWeight = r.aoaAlternativeWeight;
    o->aoaDirectionStd_rad = o->hasAoaAlternative ? r.aoaDirectionStd : o->aoaStd_rad;
    if (o->hasAoaAlternative)
        for (const auto& a : r.moreAoaAlternatives)
            o->moreAoaAlternatives.push_back({a.aoa, a.weight});
    o->hasAod = r.hasAod;
    o->aod_rad = r.aod, o->aodStd_rad = r.aodStd;
    o->aodAmbiguous = r.aodAmbiguous, o->aodMirror_rad = r.aodMirror;
    o->quality = 1;
    return o;
}

RawlogContents readRawlog(const std::string& path)
{
    if (!mrpt::system::fileExists(path)) throw std::runtime_error(path + ": rawlog not found");
    RawlogContents out;
    std::vector<std::pair<double, mrpt::math::TPose2D>> odo;
    forEachRawlogObservation(
        path,
        [&](const mrpt::obs::CObservation::Ptr& obs)
        {
            if (auto b = std::dynamic_pointer_cast<CObservationWiFiBearing>(obs))
                out.bearings.push_back(recordFromObservation(*b));
            else if (auto o = std::dynamic_pointer_cast<mrpt::obs::CObservationOdometry>(obs))
                odo.emplace_back(mrpt::Clock::toDouble(o->timestamp), o->odometry.asTPose());
            else
                out.otherObservations++;
        });
    std::stable_sort(
        odo.begin(), odo.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [t, p] : odo)
        if (out.odometry.empty() || t > out.odometry.t.back()) out.odometry.push_back(t, p);
    std::stable_sort(
        out.bearings.begin(), out.bearings.end(),
        [](const BearingRecord& a, const BearingRecord& b) { return a.t < b.t; });
    return out;
}

size_t writePfRawlog(
    const std::string& path, const std::vector<BearingRecord>& bearings, const Trajectory2D& odo)
{
    mrpt::io::CFileGZOutputStream f;
    if (!f.open(path, 0)) throw std::runtime_error(path + ": cannot write rawlog");
    auto arch = mrpt::serialization::archiveFrom(f);
    std::vector<size_t> order(bearings.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(
        order.begin(), order.end(),
        [&](size_t a, size_t b) { return bearings[a].t < bearings[b].t; });
    size_t io = 0, ib = 0, n = 0;
    while (io < odo.size() || ib < order.size())
    {
        const bool odoNext =
            io < odo.size() && (ib >= order.size() || odo.t[io] <= bearings[order[ib]].t);
        if (odoNext)
        {
            auto o = mrpt::obs::CObservationOdometry::Create();
            o->timestamp = mrpt::Clock::fromDouble(odo.t[io]);
            o->sensorLabel = "ODOMETRY";
            o->odometry = mrpt::poses::CPose2D(odo.poses[io]);
            arch << *o;
            ++io;
        }
        else
        {
            arch << *observationFromRecord(bearings[order[ib]]);
            ++ib;
        }
        ++n;
    }
    return n;
}

size_t writePfRawlogUnknownMotion(
    const std::string& path, const std::vector<BearingRecord>& bearings,
    const UnknownMotion& motion)
{
    motion.validate();
    // Readers of this rawlog (Debian's pf-localization) have no constant-velocity prediction:
    // the zero-mean walk must keep up with the robot on its own, so it takes the wide horizon
    // for every step (one Gaussian; a mixture would store 1000 samples per step).
    UnknownMotion walk = motion;
    if (walk.wideFraction > 0) walk.correlationTime_s = walk.wideCorrelationTime_s;
    walk.wideFraction = 0;
    mrpt::io::CFileGZOutputStream f;
    if (!f.open(path, 0)) throw std::runtime_error(path + ": cannot write rawlog");
    auto arch = mrpt::serialization::archiveFrom(f);
    std::vector<size_t> order(bearings.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(
        order.begin(), order.end(),
        [&](size_t a, size_t b) { return bearings[a].t < bearings[b].t; });
    size_t frames = 0;
    for (size_t i = 0; i < order.size();)
    {
        const double t = bearings[order[i]].t;
        const double dt = frames ? t - bearings[order[i - 1]].t : 0.0;
        mrpt::obs::CActionCollection acts;
        auto a = walk.makeAction(dt);
        a->timestamp = mrpt::Clock::fromDouble(t);
        acts.insert(*a);
        mrpt::obs::CSensoryFrame sf;
        for (; i < order.size() && bearings[order[i]].t == t; ++i)
            sf.insert(observationFromRecord(bearings[order[i]]));
        arch << acts << sf;
        ++frames;
    }
    return frames;
}

}  // namespace mrpt_wifi::localization
