/* Phase calibration files: format, folder layout, loader errors. */
#include <gtest/gtest.h>
#include <mrpt_wifi/obs/PhaseCalibration.h>
#include <mrpt_wifi/obs/Subcarriers.h>

#include <filesystem>
#include <fstream>

#include "TestSupport.h"

using namespace mrpt_wifi;

namespace
{
PhaseCalibration makeCalibration(const std::string& device, const Chanspec& cs, size_t antennas)
{
    PhaseCalibration c;
    c.device = device;
    c.chanspec = cs;
    c.date = "2026-11-22T10:00:00Z";
    c.framesUsed = 1234;
    c.residual_rad = 0.05;
    c.method = "unit test: Levenberg–Marquardt 'robust'";
    c.subcarriers = dataSubcarriers(cs.bandwidthMHz);
    for (size_t i = 0; i < antennas; ++i)
    {
        std::vector<double> row;
        for (int k : c.subcarriers) row.push_back(0.3 * double(i) + 0.001 * k);
        c.phases_rad.push_back(row);
    }
    c.gains_dB.assign(antennas, 0.5);
    return c;
}

std::string expectCalibrationError(const std::function<void()>& f)
{
    try
    {
        f();
    }
    catch (const CalibrationError& e)
    {
        return e.what();
    }
    ADD_FAILURE() << "no CalibrationError";
    return {};
}
}  // namespace

TEST(CalibrationFormat, RoundTripsThroughAFile)
{
    test::TempDir tmp;
    const auto cs = Chanspec::make(155, 80);
    const PhaseCalibration c = makeCalibration("rt-ac86u", cs, 4);
    const std::string path = PhaseCalibration::pathFor(tmp.path().string(), "rt-ac86u", cs);
    EXPECT_EQ(std::filesystem::path(path).filename(), "ch155_80mhz.yaml");
    c.saveYamlFile(path);
    const PhaseCalibration r = PhaseCalibration::fromYamlFile(path);
    EXPECT_EQ(r.device, "rt-ac86u");
    EXPECT_TRUE(r.matchesChannel(cs));
    EXPECT_EQ(r.framesUsed, 1234u);
    EXPECT_EQ(r.date, c.date);
    EXPECT_EQ(r.method, c.method);
    ASSERT_EQ(r.antennas(), 4u);
    ASSERT_EQ(r.subcarriers, c.subcarriers);
    for (size_t i = 0; i < 4; ++i)
        for (size_t j = 0; j < c.subcarriers.size(); ++j)
            EXPECT_NEAR(r.phases_rad[i][j], c.phases_rad[i][j], 1e-9);
    EXPECT_NEAR(r.gainAt(2), 0.5, 1e-12);
    // Interpolation between listed subcarriers (k = 0 is not a data subcarrier).
    EXPECT_NEAR(r.phaseAt(1, 0), 0.3, 1e-9);
}

TEST(CalibrationFormat, StoreFindsTheFileOfEachChannel)
{
    test::TempDir tmp;
    const auto a = Chanspec::make(155, 80), b = Chanspec::make(36 + 6, 80);
    makeCalibration("rt-ac86u", a, 4)
        .saveYamlFile(PhaseCalibration::pathFor(tmp.path().string(), "rt-ac86u", a));
    makeCalibration("rt-ac86u", b, 4)
        .saveYamlFile(PhaseCalibration::pathFor(tmp.path().string(), "rt-ac86u", b));
    const CalibrationStore store = CalibrationStore::open(tmp.path().string());
    EXPECT_TRUE(store.isFolder());
    const PhaseCalibration* ca = store.find("rt-ac86u", a, 4);
    ASSERT_NE(ca, nullptr);
    EXPECT_TRUE(ca->matchesChannel(a));
    ASSERT_NE(store.find("rt-ac86u", b, 4), nullptr);
    EXPECT_EQ(store.find("rt-ac86u", Chanspec::make(106, 80), 4), nullptr);  // none: uncalibrated
    EXPECT_EQ(store.available("rt-ac86u").size(), 2u);
}

TEST(CalibrationFormat, WrongChannelDeviceOrSizeIsAClearError)
{
    const auto cs = Chanspec::make(155, 80);
    const PhaseCalibration c = makeCalibration("rt-ac86u", cs, 4);
    std::string m =
        expectCalibrationError([&] { c.checkCompatible("rt-ac86u", Chanspec::make(42, 80), 4); });
    EXPECT_NE(m.find("155/80"), std::string::npos) << m;
    EXPECT_NE(m.find("42/80"), std::string::npos) << m;
    m = expectCalibrationError([&] { c.checkCompatible("square-2x2", cs, 4); });
    EXPECT_NE(m.find("square-2x2"), std::string::npos) << m;
    m = expectCalibrationError(
        [&] { makeCalibration("rt-ac86u", cs, 3).checkCompatible("rt-ac86u", cs, 4); });
    EXPECT_NE(m.find("3 antennas"), std::string::npos) << m;

    // A single file used for a frame on another channel fails through the store too.
    const CalibrationStore single = CalibrationStore::fromCalibration(c);
    EXPECT_THROW(single.find("rt-ac86u", Chanspec::make(42, 80), 4), CalibrationError);
    // A folder holding a file of another device under this device's name: detected.
    test::TempDir tmp;
    makeCalibration("other-router", cs, 4)
        .saveYamlFile(PhaseCalibration::pathFor(tmp.path().string(), "rt-ac86u", cs));
    EXPECT_THROW(
        CalibrationStore::open(tmp.path().string()).find("rt-ac86u", cs, 4), CalibrationError);
}

TEST(CalibrationFormat, MalformedFilesAreRejected)
{
    const auto cs = Chanspec::make(155, 80);
    const std::string good = makeCalibration("rt-ac86u", cs, 2).asYamlText();
    EXPECT_NO_THROW(PhaseCalibration::fromYamlText(good));
    const auto replaced = [&](const std::string& from, const std::string& to)
    {
        std::string s = good;
        s.replace(s.find(from), from.size(), to);
        return s;
    };
    EXPECT_THROW(
        PhaseCalibration::fromYamlText(replaced("version: 2", "version: 7")), CalibrationError);
    EXPECT_THROW(
        PhaseCalibration::fromYamlText(replaced("antennas: 2", "antennas: 3")), CalibrationError);
    EXPECT_THROW(
        PhaseCalibration::fromYamlText(replaced("chanspec: 155/80", "chanspec: 999/80")),
        CalibrationError);
    EXPECT_THROW(
        PhaseCalibration::fromYamlText(replaced("subcarriers: [-122", "subcarriers: [-200")),
        CalibrationError);
    EXPECT_THROW(
        PhaseCalibration::fromYamlText(
            replaced("format: mrpt_wifi_phase_calibration", "format: other")),
        CalibrationError);
    EXPECT_THROW(PhaseCalibration::fromYamlText(good + "colour: blue\n"), CalibrationError);
    EXPECT_THROW(CalibrationStore::open("/nonexistent/calib"), CalibrationError);
}
