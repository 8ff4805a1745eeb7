/* mrpt_wifi — WiFi channel state information for MRPT.  */
#include <gtest/gtest.h>
#include <mrpt/bayes/CParticleFilter.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/maps/CMultiMetricMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPosePDFParticles.h>
#include <mrpt/random/RandomGenerators.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/slam/CMonteCarloLocalization2D.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/localization/BearingLikelihood.h>
#include <mrpt_wifi/localization/CWiFiBearingMap.h>
#include <mrpt_wifi/localization/ParticleRecovery.h>
#include <mrpt_wifi/localization/RawlogIO.h>

#include <Eigen/Dense>
#include <fstream>

#include "SyntheticWorld.h"
#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::localization;
using namespace mrpt_wifi::loctest;

namespace
{
const char* kApsYaml = R"(transmitters:
  - name: nw
    mac: '02:00:00:00:0a:01'
    position: [0.3, 4.7]
    yaw_deg: -45
    array_elements: [[0, -0.039], [0, 0.039]]
  - name: se
    mac: '02:00:00:00:0a:02'
    position: [9.7, 0.3]
    yaw_deg: 135
    array_elements: [[0, -0.039], [0, 0.039]]
  - name: ne
    mac: '02:00:00:00:0a:03'
    position: [9.7, 4.7]
    yaw_deg: -135
    array_elements: [[0, -0.039], [0, 0.039]]
)";

std::string writeTemp(const std::string& name, const std::string& text)
{
    const std::string path = mrpt_wifi::test::tempPath() + "_" + name;
    std::ofstream(path) << text;
    return path;
}

std::string iniFor(const std::string& apsFile, const std::string& mapName = "wifiBearingMap")
{
    return "[MetricMap]\n" + mapName + "_count=1\n[MetricMap_" + mapName +
           "_00_creationOpts]\ntransmitters_file=" + apsFile + "\n[MetricMap_" + mapName +
           "_00_likelihoodOpts]\nmin_std_deg=3\n";
}

mrpt::maps::CMultiMetricMap mapFromIni(const std::string& ini)
{
    mrpt::config::CConfigFileMemory cfg;
    cfg.setContent(ini);
    mrpt::maps::TSetOfMetricMapInitializers inits;
    inits.loadFromConfigFile(cfg, "MetricMap");
    mrpt::maps::CMultiMetricMap m;
    m.setListOfMaps(inits);
    return m;
}
}  // namespace

TEST(BearingMapRegistration, IniCreatesTheMapByShortAndFullName)
{
    const auto aps = writeTemp("aps.yaml", kApsYaml);
    auto m = mapFromIni(iniFor(aps));
    const auto wm = m.mapByClass<CWiFiBearingMap>();
    ASSERT_TRUE(wm) << "wifiBearingMap_count=1 did not create a CWiFiBearingMap";
    EXPECT_EQ(wm->transmitters().size(), 3u);
    EXPECT_EQ(wm->transmitters().at(1).name, "se");
    // MRPT ignores unknown names silently: a typo creates nothing (why the test above matters).
    auto typo = mapFromIni(iniFor(aps, "wifiBearingMapp"));
    EXPECT_FALSE(typo.mapByClass<CWiFiBearingMap>());
}

TEST(BearingMapRegistration, MissingTransmittersFileIsAnError)
{
    EXPECT_ANY_THROW(mapFromIni("[MetricMap]\nwifiBearingMap_count=1\n"));
    EXPECT_ANY_THROW(mapFromIni(iniFor("/nonexistent/aps.yaml")));
}

TEST(BearingMapFile, DuplicateMacsAndUnknownKeysAreErrors)
{
    const std::string dup =
        std::string(kApsYaml) + "  - {name: again, mac: '02:00:00:00:0A:01', position: [1, 1]}\n";
    try
    {
        TransmitterMap::fromYamlText(dup, "dup.yaml");
        FAIL() << "duplicate MAC accepted";
    }
    catch (const std::runtime_error& e)
    {
        EXPECT_NE(std::string(e.what()).find("duplicate MAC 02:00:00:00:0a:01"), std::string::npos)
            << e.what();
        EXPECT_NE(std::string(e.what()).find("dup.yaml:"), std::string::npos) << e.what();
    }
    EXPECT_THROW(
        TransmitterMap::fromYamlText("transmitters:\n  - {mac: '02:00:00:00:00:01', "
                                     "position: [0, 0], yawdeg: 3}\n"),
        std::runtime_error);
    EXPECT_THROW(
        TransmitterMap::fromYamlText("transmitters:\n  - {mac: 'zz', position: [0, 0]}\n"),
        std::runtime_error);
}

TEST(BearingMapFile, ArrayGeometryAndMirror)
{
    const auto g = ArrayGeometry::fromElements({{0, 0}, {0, 0.052}, {0, 0.026}, {0, 0.078}});
    EXPECT_TRUE(g.linear);
    EXPECT_NEAR(g.axis_rad, M_PI / 2, 1e-12);
    EXPECT_NEAR(g.mirrorOf(0.3), M_PI - 0.3, 1e-12);  // front/back mirror for an array along y
    EXPECT_TRUE(g.inFrontHalf(0.3));
    EXPECT_FALSE(g.inFrontHalf(M_PI - 0.3));
    const auto sq = ArrayGeometry::fromElements({{0, 0}, {0.03, 0}, {0, 0.03}, {0.03, 0.03}});
    EXPECT_FALSE(sq.linear);
    EXPECT_NEAR(sq.mirrorOf(0.3), 0.3, 1e-12);
}

namespace
{
/** `ap`'s AoA exactly as seen from `robot`, with σ `std`. */
BearingRecord exactAoa(const KnownTransmitter& ap, const mrpt::math::TPose2D& robot, double std)
{
    BearingRecord r;
    r.t = 1;
    r.transmitter = ap.mac;
    r.hasAoa = true;
    r.aoaStd = std;
    r.aoa = predictAoa(sensorWorldPose(robot, r.sensorPose), ap.pose.x, ap.pose.y);
    return r;
}
}  // namespace

TEST(BearingMapLikelihood, PeaksAtTheTruePoseAndIsMirrorAware)
{
    CWiFiBearingMap map;
    map.setTransmitters(TransmitterMap::fromYamlText(kApsYaml));
    const auto& ap = map.transmitters().at(0);
    const mrpt::math::TPose2D robot(4, 2, 0.3);
    BearingRecord r = exactAoa(ap, robot, 0.05);
    const auto s = sensorWorldPose(robot, r.sensorPose);
    r.hasAod = true;
    r.aodStd = 0.05;
    r.aod = predictAod(ap.pose, s.x, s.y);
    auto obs = observationFromRecord(r);
    const auto at = [&](double x, double y, double yaw)
    { return map.computeObservationLikelihood(*obs, mrpt::poses::CPose3D(x, y, 0, yaw, 0, 0)); };
    const double best = at(robot.x, robot.y, robot.phi);
    EXPECT_GT(best, at(robot.x + 0.5, robot.y, robot.phi) + 1);
    EXPECT_GT(best, at(robot.x, robot.y, robot.phi + 0.3) + 1);
    // Outliers are bounded: an absurd pose is unlikely but not -inf.
    EXPECT_TRUE(std::isfinite(at(9, 4, 3)));

    // Ambiguous AoA: the robot turned around by the mirror is as likely (AoA alone).
    map.likelihoodOptions.use.aod = false;
    r.aoaAmbiguous = true;
    r.aoaMirror = wrapToPi(M_PI - r.aoa);  // mirror across an array along y
    obs = observationFromRecord(r);
    const double trueYaw = at(robot.x, robot.y, robot.phi);
    // Heading that makes the mirror candidate exact: world bearing = yaw + mirror.
    const double worldBearing = robot.phi + r.aoa;
    const double mirrorYaw = worldBearing - r.aoaMirror;
    EXPECT_NEAR(at(robot.x, robot.y, mirrorYaw), trueYaw, 1e-6);
    r.aoaAmbiguous = false;
    obs = observationFromRecord(r);
    EXPECT_GT(at(robot.x, robot.y, robot.phi), at(robot.x, robot.y, mirrorYaw) + 1);
}

TEST(BearingMapLikelihood, AnAlternativeDirectionIsWeighedAsAMixture)
{
    // A window near endfire: its σ (80°) reaches the other endfire, which came as close; each
    // direction alone is sharp (4°). With aoa_alternative_share the map weighs the two
    // directions; without, the wide σ is beyond max_std_deg and the bearing says nothing.
    CWiFiBearingMap map;
    map.setTransmitters(TransmitterMap::fromYamlText(kApsYaml));
    map.likelihoodOptions.use.aod = false;
    map.likelihoodOptions.model.minStd_rad = mrpt::DEG2RAD(2.0);
    const auto& ap = map.transmitters().at(0);
    const mrpt::math::TPose2D robot(4, 2, 0.3);
    BearingRecord r = exactAoa(ap, robot, mrpt::DEG2RAD(80.0));
    r.hasAoaAlternative = true;
    r.aoaAlternative = wrapToPi(r.aoa + mrpt::DEG2RAD(150.0));
    r.aoaAlternativeWeight = 1;
    r.aoaDirectionStd = mrpt::DEG2RAD(4.0);
    const auto obs = observationFromRecord(r);
    const auto at = [&](double yaw)
    {
        return map.computeObservationLikelihood(
            *obs, mrpt::poses::CPose3D(robot.x, robot.y, 0, yaw, 0, 0));
    };
    // Heading whose prediction lands on the alternative, and one that lands on neither.
    const double onAlternative = robot.phi + r.aoa - r.aoaAlternative;
    const double onNeither = robot.phi + mrpt::DEG2RAD(60.0);

    EXPECT_EQ(at(robot.phi), 0.0) << "share 0: a σ beyond max_std_deg is not weighed";
    map.likelihoodOptions.model.aoaAlternativeShare = 0.1;
    EXPECT_GT(at(robot.phi), at(onAlternative) + 1) << "the chosen direction weighs most";
    EXPECT_GT(at(onAlternative), at(onNeither) + 1) << "the alternative still explains a pose";
    // The alternative's weight in the mixture follows the share and the window's weight.
    const double fullWeight = at(onAlternative);
    map.likelihoodOptions.model.aoaAlternativeShare = 0.02;
    EXPECT_LT(at(onAlternative), fullWeight - 1);

    // A window without an alternative is weighed as before, whatever the share.
    r.hasAoaAlternative = false;
    r.aoaStd = mrpt::DEG2RAD(4.0);
    const auto sure = observationFromRecord(r);
    const mrpt::poses::CPose3D offPose(robot.x, robot.y, 0, robot.phi + 0.05, 0, 0);
    const double withShare = map.computeObservationLikelihood(*sure, offPose);
    map.likelihoodOptions.model.aoaAlternativeShare = 0;
    EXPECT_DOUBLE_EQ(withShare, map.computeObservationLikelihood(*sure, offPose));
}

TEST(BearingMapLikelihood, WeighedAlternativesKeepTheTruthAgainstReflections)
{
    // Issue 53 (room 2): three APs' strongest paths are reflections that all fit one wrong
    // pose better than the truth (the filter converged there: log-likelihood 1939 against 1804
    // at the truth). Each bearing carries two alternatives, as the estimators measure them: a
    // second reflection that fits nothing (weight 0.4) and the direct path (0.35). Weighed as a
    // mixture of all of them, the truth is the most likely pose; with one direction per bearing,
    // or the first alternative only, the wrong pose wins.
    CWiFiBearingMap map;
    map.setTransmitters(
        makeAps({{0.3, 7.7, -0.785}, {9.7, 7.7, -2.36}, {9.7, 0.3, 2.36}, {0.3, 0.3, 0.785}}));
    map.likelihoodOptions.use.aod = false;
    const mrpt::math::TPose2D truth(4, 3, 0.3), wrong(4, 4.2, 0.3);
    std::vector<BearingRecord> records;
    for (size_t i = 0; i < 4; ++i)
    {
        const auto& ap = map.transmitters().at(i);
        BearingRecord r = exactAoa(ap, truth, mrpt::DEG2RAD(2.0));
        if (i < 3)
        {
            r.hasAoaAlternative = true;
            r.aoaAlternative = wrapToPi(r.aoa + mrpt::DEG2RAD(70.0));
            r.aoaAlternativeWeight = 0.4;
            r.moreAoaAlternatives = {{r.aoa, 0.35}};
            r.aoaDirectionStd = r.aoaStd;
            r.aoa = exactAoa(ap, wrong, r.aoaStd).aoa;  // the reflection, reported
        }
        records.push_back(r);
    }
    const auto logLikelihood = [&](const std::vector<BearingRecord>& rs, double x, double y)
    {
        double ll = 0;
        for (const auto& r : rs)
            ll += map.computeObservationLikelihood(
                *observationFromRecord(r), mrpt::poses::CPose3D(x, y, 0, truth.phi, 0, 0));
        return ll;
    };
    const auto bestPosition = [&](const std::vector<BearingRecord>& rs)
    {
        double best = -INFINITY;
        mrpt::math::TPoint2D at;
        for (double x = 0.5; x < 9.5; x += 0.05)
            for (double y = 0.5; y < 7.5; y += 0.05)
                if (const double ll = logLikelihood(rs, x, y); ll > best) best = ll, at = {x, y};
        return at;
    };
    const auto fromTruth = [&](const mrpt::math::TPoint2D& a)
    { return std::hypot(a.x - truth.x, a.y - truth.y); };
    auto firstOnly = records;
    for (auto& r : firstOnly) r.moreAoaAlternatives.clear();

    map.likelihoodOptions.model.aoaAlternativeShare = 0;
    EXPECT_GT(logLikelihood(records, wrong.x, wrong.y), logLikelihood(records, truth.x, truth.y))
        << "one direction each: the reflections win";
    map.likelihoodOptions.model.aoaAlternativeShare = 1;
    EXPECT_GT(
        logLikelihood(firstOnly, wrong.x, wrong.y), logLikelihood(firstOnly, truth.x, truth.y))
        << "the first alternative only: the reflections win";
    EXPECT_GT(logLikelihood(records, truth.x, truth.y), logLikelihood(records, wrong.x, wrong.y))
        << "the mixture of all alternatives keeps the truth";
    const auto mixture = bestPosition(records);
    EXPECT_LT(fromTruth(mixture), 0.15)
        << "its most likely pose: " << mixture.x << ", " << mixture.y;
}

TEST(BearingMapLikelihood, ZeroForOtherObservationsAndUnknownTransmitters)
{
    CWiFiBearingMap map;
    map.setTransmitters(TransmitterMap::fromYamlText(kApsYaml));
    mrpt::obs::CObservationOdometry odo;
    EXPECT_EQ(map.computeObservationLikelihood(odo, mrpt::poses::CPose3D()), 0.0);
    EXPECT_FALSE(map.canComputeObservationLikelihood(odo));
    BearingRecord r;
    r.transmitter = MacAddress::fromString("02:00:00:00:ff:ff");
    r.hasAoa = true, r.aoaStd = 0.05;
    const auto obs = observationFromRecord(r);
    for (int i = 0; i < 10; ++i)  // as 10 particles would
        EXPECT_EQ(
            map.computeObservationLikelihood(*obs, mrpt::poses::CPose3D(i, 0, 0, 0, 0, 0)), 0.0);
    EXPECT_EQ(map.unknownTransmitterCount(), 1u);  // once per observation, not per particle
    EXPECT_EQ(map.unknownTransmitters().count(r.transmitter), 1u);
}

TEST(BearingMapSerialization, RoundTrip)
{
    CWiFiBearingMap map;
    map.setTransmitters(TransmitterMap::fromYamlText(kApsYaml));
    map.likelihoodOptions.model.outlierProb = 0.2;
    map.likelihoodOptions.model.aoaAlternativeShare = 0.05;
    mrpt::io::CMemoryStream buf;
    auto arch = mrpt::serialization::archiveFrom(buf);
    arch << map;
    buf.Seek(0);
    auto obj = arch.ReadObject();
    auto back = std::dynamic_pointer_cast<CWiFiBearingMap>(obj);
    ASSERT_TRUE(back);
    EXPECT_EQ(back->transmitters().size(), 3u);
    EXPECT_NEAR(back->transmitters().at(2).pose.phi, mrpt::DEG2RAD(-135.0), 1e-9);
    EXPECT_DOUBLE_EQ(back->likelihoodOptions.model.outlierProb, 0.2);
    EXPECT_DOUBLE_EQ(back->likelihoodOptions.model.aoaAlternativeShare, 0.05);
}

// The map inside MRPT's own Monte Carlo localization, initialised uniformly over the room (the
// kidnapped robot), fed one bearing per step as pf-localization does with observation-only
// rawlogs.
TEST(BearingMapParticleFilter, GlobalLocalizationConverges)
{
    const auto aps =
        makeAps({{0.3, 4.7, -0.785}, {9.7, 4.7, -2.36}, {9.7, 0.3, 2.36}, {0.3, 0.3, 0.785}});
    WorldOptions wo;
    wo.duration_s = 60;
    const auto w = makeWorld(aps, wo);
    const auto apsFile = writeTemp("aps.yaml", aps.asYamlText());
    auto mm = std::make_shared<mrpt::maps::CMultiMetricMap>(mapFromIni(iniFor(apsFile)));

    // Seeded: MRPT's global generator starts from the clock. Plain MCL has no recovery (the
    // apps add ParticleRecovery), so a start that resamples onto a wrong mode stays there: over
    // seeds 1-30, seed 3 held one 4.5 m off and the other 29 converged.
    mrpt::random::getRandomGenerator().randomize(1);
    mrpt::slam::CMonteCarloLocalization2D pdf;
    pdf.options.metricMap = mm;
    pdf.resetUniform(0, 10, 0, 5, -M_PI, M_PI, 2000);
    mrpt::bayes::CParticleFilter pf;
    pf.m_options.PF_algorithm = mrpt::bayes::CParticleFilter::pfStandardProposal;
    pf.m_options.BETA = 0.5;
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions mo;
    mo.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
    mo.gaussianModel.minStdXY = 0.01;
    mo.gaussianModel.minStdPHI = mrpt::DEG2RAD(0.5);

    mrpt::math::TPose2D lastOdo = w.odometry.poses.front();
    std::vector<double> errs;
    for (const auto& b : w.bearings)
    {
        mrpt::math::TPose2D o;
        ASSERT_TRUE(w.odometry.interpolate(b.t, o));
        mrpt::obs::CActionRobotMovement2D act;
        act.computeFromOdometry(mrpt::poses::CPose2D(o) - mrpt::poses::CPose2D(lastOdo), mo);
        lastOdo = o;
        mrpt::obs::CActionCollection acts;
        acts.insert(act);
        mrpt::obs::CSensoryFrame sf;
        sf.insert(observationFromRecord(b));
        pf.executeOn(pdf, &acts, &sf);
        mrpt::math::TPose2D gt;
        ASSERT_TRUE(w.truth.interpolate(b.t, gt));
        const auto mean = pdf.getMeanVal();
        errs.push_back(std::hypot(mean.x() - gt.x, mean.y() - gt.y));
    }
    // After 20 s (of 60), the error must be small everywhere.
    std::vector<double> late(errs.begin() + long(errs.size() / 3), errs.end());
    const auto st = computeStats(late);
    EXPECT_LT(st.median, 0.3) << st.asString();
    EXPECT_LT(st.max, 1.0) << st.asString();
}

TEST(BearingMapArea, PosesOutsideTheAreaLoseTheirWeightAndTheAreaIsSaved)
{
    const auto aps = writeTemp("area_aps.yaml", kApsYaml);
    const std::string sect = "[MetricMap_wifiBearingMap_00_creationOpts]\n";
    auto m = mapFromIni(iniFor(aps) + sect + "min_x=0\nmax_x=10\nmin_y=0\nmax_y=5\n");
    auto map = m.mapByClass<CWiFiBearingMap>();
    ASSERT_TRUE(map && map->area());
    EXPECT_TRUE(map->inArea(9.9, 4.9));
    EXPECT_FALSE(map->inArea(10.1, 2));
    EXPECT_FALSE(map->inArea(5, -0.1));
    // A bearing that fits a pose just outside perfectly still scores the outside floor there.
    const auto& ap = map->transmitters().at(0);
    const mrpt::math::TPose2D outside(10.2, 2, 0.3);
    BearingRecord r;
    r.t = 1, r.transmitter = ap.mac, r.hasAoa = true, r.aoaStd = 0.05;
    const auto s = sensorWorldPose(outside, r.sensorPose);
    r.aoa = predictAoa(s, ap.pose.x, ap.pose.y);
    const auto obs = observationFromRecord(r);
    EXPECT_EQ(
        map->computeObservationLikelihood(
            *obs, mrpt::poses::CPose3D(outside.x, outside.y, 0, 0.3, 0, 0)),
        CWiFiBearingMap::kOutsideAreaLogLikelihood);
    EXPECT_GT(
        map->computeObservationLikelihood(*obs, mrpt::poses::CPose3D(9.8, 2, 0, 0.3, 0, 0)),
        CWiFiBearingMap::kOutsideAreaLogLikelihood + 20);
    EXPECT_TRUE(map->agrees(*obs, outside).value_or(false));
    EXPECT_FALSE(map->agrees(*obs, {outside.x, outside.y, outside.phi + 0.5}).value_or(true));

    // Serialized (a map in a rawlog or .simplemap) with its area.
    mrpt::io::CMemoryStream buf;
    mrpt::serialization::archiveFrom(buf) << *map;
    buf.Seek(0);
    CWiFiBearingMap back;
    mrpt::serialization::archiveFrom(buf) >> back;
    ASSERT_TRUE(back.area());
    EXPECT_EQ(back.area()->max.x, 10.0);
    EXPECT_EQ(back.area()->max.y, 5.0);

    // Three of the four keys, or an empty box: an error naming the keys.
    for (const std::string bad :
         {"min_x=0\nmax_x=10\nmin_y=0\n", "min_x=3\nmax_x=3\nmin_y=0\nmax_y=5\n"})
    {
        try
        {
            mapFromIni(iniFor(aps) + sect + bad);
            ADD_FAILURE() << "accepted " << bad;
        }
        catch (const std::exception& e)
        {
            EXPECT_NE(std::string(e.what()).find("min_x"), std::string::npos) << e.what();
        }
    }
}

TEST(BearingMapWeight, TempersEachBearingAndIsSavedWithTheMap)
{
    const auto aps = writeTemp("weight_aps.yaml", kApsYaml);
    const std::string sect = "[MetricMap_wifiBearingMap_00_likelihoodOpts]\n";
    auto full = mapFromIni(iniFor(aps)).mapByClass<CWiFiBearingMap>();
    auto tempered =
        mapFromIni(iniFor(aps) + sect + "bearing_weight = 0.3\n").mapByClass<CWiFiBearingMap>();
    ASSERT_TRUE(full && tempered);
    EXPECT_EQ(full->likelihoodOptions.bearingWeight, 1.0);
    EXPECT_EQ(tempered->likelihoodOptions.bearingWeight, 0.3);
    const auto& ap = full->transmitters().at(0);
    BearingRecord r;
    r.t = 1, r.transmitter = ap.mac, r.hasAoa = true, r.aoaStd = 0.05;
    const mrpt::math::TPose2D robot(4, 2, 0.3);
    r.aoa = predictAoa(sensorWorldPose(robot, r.sensorPose), ap.pose.x, ap.pose.y) + 0.1;
    const auto obs = observationFromRecord(r);
    for (const double yaw : {0.3, 1.0, 2.5})
    {
        const mrpt::poses::CPose3D p(robot.x, robot.y, 0, yaw, 0, 0);
        EXPECT_NEAR(
            tempered->computeObservationLikelihood(*obs, p),
            0.3 * full->computeObservationLikelihood(*obs, p), 1e-12);
    }

    mrpt::io::CMemoryStream buf;
    mrpt::serialization::archiveFrom(buf) << *tempered;
    buf.Seek(0);
    CWiFiBearingMap back;
    mrpt::serialization::archiveFrom(buf) >> back;
    EXPECT_EQ(back.likelihoodOptions.bearingWeight, 0.3);

    // (Read through the options: MRPT's TSetOfMetricMapInitializers leaks the map definition
    // when its loading throws, which the sanitizer build reports.)
    for (const std::string bad :
         {"bearing_weight = 0\n", "bearing_weight = 1.5\n", "use_aoa = false\nuse_aod = false\n"})
    {
        try
        {
            mrpt::config::CConfigFileMemory cfg(sect + bad);
            CWiFiBearingMap::TLikelihoodOptions o;
            o.loadFromConfigFile(cfg, "MetricMap_wifiBearingMap_00_likelihoodOpts");
            ADD_FAILURE() << "accepted " << bad;
        }
        catch (const std::exception& e)
        {
            EXPECT_NE(std::string(e.what()).find(bad.substr(0, bad.find(' '))), std::string::npos)
                << e.what();
        }
    }
}

TEST(ParticleRecovery, ReseedsOnlyWhileMostBearingsDisagreeWithTheEstimate)
{
    CWiFiBearingMap map;
    map.setTransmitters(TransmitterMap::fromYamlText(kApsYaml));
    map.setArea(mrpt::math::TBoundingBox({0, 0, 0}, {10, 5, 0}));
    const mrpt::math::TPose2D robot(4, 2, 0.3);
    const auto bearingsAt = [&](double t)
    {
        std::vector<CObservationWiFiBearing::Ptr> out;
        for (const auto& ap : map.transmitters().transmitters())
        {
            BearingRecord r;
            r.t = t, r.transmitter = ap.mac, r.hasAoa = true, r.aoaStd = 0.05;
            r.aoa = predictAoa(sensorWorldPose(robot, r.sensorPose), ap.pose.x, ap.pose.y);
            out.push_back(observationFromRecord(r));
        }
        return out;
    };
    const auto feed = [&](ParticleRecovery& rec, const mrpt::math::TPose2D& estimate)
    {
        double fraction = 0;
        rec.setEstimate(estimate);
        for (int k = 0; k < 40; ++k)  // 4 s of steps at 10/s
        {
            const double t = 0.1 * k;
            for (const auto& b : bearingsAt(t)) rec.checkBearing(t, *b);
            fraction = rec.reseedFraction(t, 0.1);
        }
        return fraction;
    };
    ParticleRecoveryOptions o;  // 1/s, 2 s window, half must agree
    ParticleRecovery agreeing(o, &map);
    EXPECT_EQ(feed(agreeing, {4.05, 2.0, 0.3}), 0.0);
    EXPECT_EQ(agreeing.recoveryEpisodes(), 0u);
    ParticleRecovery lost(o, &map);
    EXPECT_NEAR(feed(lost, {8, 4, -2}), 1 - std::exp(-0.1), 1e-9);
    EXPECT_EQ(lost.recoveryEpisodes(), 1u);
    EXPECT_NEAR(lost.reseedRadius_m(), std::hypot(10.0, 5.0), 1e-9);
    // An estimate outside the area disagrees with everything.
    ParticleRecovery outside(o, &map);
    EXPECT_GT(feed(outside, {10.5, 2, 0.3}), 0.0);
    // No area, no recovery (nowhere to re-seed).
    CWiFiBearingMap unbounded;
    unbounded.setTransmitters(map.transmitters());
    ParticleRecovery noArea(o, &unbounded);
    EXPECT_EQ(feed(noArea, {8, 4, -2}), 0.0);
    // Bad options name the key.
    mrpt::config::CConfigFileMemory bad("[ParticleRecovery]\nmin_agreement = 1.5\n");
    try
    {
        o.loadFromConfigFile(bad, "ParticleRecovery");
        ADD_FAILURE() << "accepted min_agreement = 1.5";
    }
    catch (const std::invalid_argument& e)
    {
        EXPECT_NE(std::string(e.what()).find("min_agreement"), std::string::npos);
    }
}

TEST(ParticleRecovery, ReseedingJumpsCoverTheAreaUniformly)
{
    // The action keeps (1 - f) of its own motion; f of it jumps uniformly within the disc whose
    // radius is the area's diagonal, with any heading. Seeded: MRPT's global generator starts
    // from the clock, and 200 jumps leave the outer-half share a binomial spread.
    mrpt::random::getRandomGenerator().randomize(11);
    mrpt::obs::CActionRobotMovement2D::TMotionModelOptions mm;
    mm.modelSelection = mrpt::obs::CActionRobotMovement2D::mmGaussian;
    mrpt::obs::CActionRobotMovement2D odo;
    odo.computeFromOdometry(mrpt::poses::CPose2D(0.05, 0, 0), mm);
    const double radius = std::hypot(10.0, 5.0);
    const auto a = withReseeding(odo, 0.2, radius);
    const auto* pdf = dynamic_cast<const mrpt::poses::CPosePDFParticles*>(a.poseChange.get());
    ASSERT_NE(pdf, nullptr);
    size_t jumps = 0, farOut = 0, inOuterHalf = 0;
    for (const auto& p : pdf->m_particles)
    {
        const double d = std::hypot(p.d.x, p.d.y);
        if (d > 1.0)
        {
            ++jumps;
            inOuterHalf += d > radius / std::sqrt(2.0) ? 1 : 0;  // half the disc's area
        }
        farOut += d > radius + 1e-9 ? 1 : 0;
    }
    EXPECT_NEAR(double(jumps) / double(pdf->size()), 0.2 * (1 - 1.0 / (radius * radius)), 0.02);
    EXPECT_EQ(farOut, 0u);
    // Half the disc's area: a binomial share, within 4 of its standard deviations.
    EXPECT_NEAR(double(inOuterHalf) / double(jumps), 0.5, 4 * std::sqrt(0.25 / double(jumps)));
    // No re-seeding: the action untouched.
    EXPECT_EQ(
        withReseeding(odo, 0.0, radius).poseChange.get()->GetRuntimeClass(),
        odo.poseChange.get()->GetRuntimeClass());
}

TEST(SharpCoverage, CountsTheTransmittersWithASharpBearingInEachSecond)
{
    // What tells a user a room can't be localized without odometry: a pose needs 3 sharp
    // transmitters at once. Second 0: a and b sharp, c wide; second 1: a (twice), b and c
    // sharp; second 2: nothing heard; second 3: d's AoD only.
    const auto mac = [](int i)
    { return MacAddress::fromString("02:00:00:00:0a:0" + std::to_string(i)); };
    const auto aoa = [&](double t, int tx, double std_deg)
    {
        BearingRecord r;
        r.t = 100 + t, r.transmitter = mac(tx), r.hasAoa = true, r.aoaStd = mrpt::DEG2RAD(std_deg);
        return r;
    };
    BearingRecord aodOnly;
    aodOnly.t = 103.5, aodOnly.transmitter = mac(4), aodOnly.hasAod = true;
    aodOnly.aodStd = mrpt::DEG2RAD(4);
    const std::vector<BearingRecord> records = {aoa(0.1, 1, 3), aoa(0.5, 2, 9), aoa(0.9, 3, 30),
                                                aoa(1.2, 1, 2), aoa(1.4, 1, 2), aoa(1.6, 2, 5),
                                                aoa(1.8, 3, 8), aodOnly};
    const auto c = sharpCoverage(records, BearingUse{true, true}, mrpt::DEG2RAD(10));
    EXPECT_EQ(c.seconds(), 4u);
    EXPECT_EQ(c.secondsWith, (std::array<size_t, 4>{1, 1, 1, 1}));
    EXPECT_DOUBLE_EQ(c.shareWithAtLeast(3), 0.25);
    EXPECT_DOUBLE_EQ(c.shareWithAtLeast(2), 0.5);
    EXPECT_EQ(
        c.asString(),
        "3+ transmitters with a sharp bearing in 25 % of 4 s (2: 25 %, 1: 25 %, 0: 25 %)");
    // Angles the map does not weigh are not sharp: AoA only, d's second has none.
    const auto aoaOnly = sharpCoverage(records, BearingUse{true, false}, mrpt::DEG2RAD(10));
    EXPECT_EQ(aoaOnly.secondsWith, (std::array<size_t, 4>{2, 0, 1, 1}));
    // A stricter σ: c's 8° no longer counts in second 1, and b's 9° not in second 0.
    const auto strict = sharpCoverage(records, BearingUse{true, true}, mrpt::DEG2RAD(6));
    EXPECT_EQ(strict.secondsWith, (std::array<size_t, 4>{1, 2, 1, 0}));
    EXPECT_EQ(sharpCoverage({}, BearingUse{}, 1.0).asString(), "no bearings");
    EXPECT_TRUE(std::isnan(sharpCoverage({}, BearingUse{}, 1.0).shareWithAtLeast(3)));
}

TEST(BearingBias, CovarianceIsTheInverseFisherInformationOfOneBearingPerTransmitter)
{
    // The Jacobians of AoA and AoD (with the array off the robot's centre) checked by finite
    // differences of predictAoa() / predictAod(), so the analytic derivative cannot hide an
    // error.
    const mrpt::math::TPose2D robot(3, 2, 0.4), sensor(0.1, 0.05, 0.2);
    const std::vector<mrpt::math::TPoint2D> spread = {{0, 0}, {8, 1}, {4, 7}};
    const double bias = mrpt::DEG2RAD(3.0), prior = 50.0;
    for (const BearingUse use : {BearingUse{true, false}, BearingUse{false, true}})
    {
        Eigen::Matrix3d info =
            Eigen::Vector3d(1 / (prior * prior), 1 / (prior * prior), 1 / (M_PI * M_PI))
                .asDiagonal();
        for (const auto& tx : spread)
        {
            const auto angle = [&](const mrpt::math::TPose2D& p)
            {
                const auto s = sensorWorldPose(p, sensor);
                return use.aoa ? predictAoa(s, tx.x, tx.y)
                               : predictAod(mrpt::math::TPose2D(tx.x, tx.y, 0.7), s.x, s.y);
            };
            Eigen::Vector3d j;
            for (int k = 0; k < 3; ++k)
            {
                auto plus = robot, minus = robot;
                const double h = 1e-6;
                (k == 0 ? plus.x : k == 1 ? plus.y : plus.phi) += h;
                (k == 0 ? minus.x : k == 1 ? minus.y : minus.phi) -= h;
                j[k] = wrapToPi(angle(plus) - angle(minus)) / (2 * h);
            }
            info += j * j.transpose() / (bias * bias);
        }
        const Eigen::Matrix3d expected = info.inverse();
        const auto cov = bearingBiasCovariance(robot, sensor, spread, use, bias, prior);
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(cov(r, c), expected(r, c), 1e-5 * std::abs(expected(r, c)) + 1e-12)
                    << (use.aoa ? "AoA" : "AoD") << " (" << r << ", " << c << ")";
    }
    const BearingUse aoa{true, false};
    const auto cov = bearingBiasCovariance(robot, sensor, spread, aoa, bias, prior);
    // Well spread transmitters a few metres away: a 3 degree bias is decimetres.
    const double sigmaSpread = std::sqrt(std::max(cov(0, 0), cov(1, 1)));
    EXPECT_GT(sigmaSpread, 0.05);
    EXPECT_LT(sigmaSpread, 0.5);
    // Two of them side by side (a room with two APs 0.1 m apart): the pose is much less fixed.
    const auto sideBySide =
        bearingBiasCovariance(robot, sensor, {{0, 0}, {8, 1}, {8.1, 1}}, aoa, bias, prior);
    EXPECT_GT(sideBySide(0, 0) + sideBySide(1, 1), 4 * (cov(0, 0) + cov(1, 1)));
    // Nothing heard: the prior alone, large but finite.
    const auto none = bearingBiasCovariance(robot, sensor, {}, aoa, bias, prior);
    EXPECT_NEAR(none(0, 0), prior * prior, 1e-6 * prior * prior);
}
