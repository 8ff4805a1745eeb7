/* Antenna arrays: file format, geometry, steering convention, mirror ambiguity, CRB. */
#include <gtest/gtest.h>
#include <mrpt_wifi/obs/AntennaArray.h>

#include <cmath>

#include "SyntheticCsi.h"

using namespace mrpt_wifi;

TEST(ArrayFile, LoadsEveryShippedArray)
{
    for (const char* n : {"rt-ac86u", "square-2x2", "ap-linear-2", "ap-linear-4"})
    {
        const AntennaArray a = test::loadArray(n);
        EXPECT_EQ(a.name, n);
        EXPECT_GE(a.size(), 2u);
    }
    const AntennaArray r = test::loadArray("rt-ac86u");
    ASSERT_EQ(r.size(), 4u);
    EXPECT_DOUBLE_EQ(r.elements[1].y, 0.052);  // port order 0, 2, 1, 3 along the line
    EXPECT_DOUBLE_EQ(r.elements[2].y, 0.026);
}

TEST(ArrayFile, RoundTripsThroughText)
{
    const AntennaArray a = test::loadArray("square-2x2");
    const AntennaArray b = AntennaArray::fromYamlText(a.asYamlText());
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i)
    {
        EXPECT_NEAR(a.elements[i].x, b.elements[i].x, 1e-12);
        EXPECT_NEAR(a.elements[i].y, b.elements[i].y, 1e-12);
    }
}

TEST(ArrayFile, BadFilesGiveClearErrors)
{
    const auto expectError = [](const std::string& text, const std::string& fragment)
    {
        try
        {
            AntennaArray::fromYamlText(text, "t.yaml");
            FAIL() << "accepted: " << text;
        }
        catch (const std::runtime_error& e)
        {
            EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("t.yaml"), std::string::npos) << e.what();
        }
    };
    expectError("elements: [[0, 0]]", "name");
    expectError("name: x\nelements: []", "elements");
    expectError("name: x\nelements: [[0, 0], [0, 0]]", "coincides");
    expectError("name: x\nelements: [[0, 0, 1]]", "[x, y]");
    expectError("name: x\nelements: [[0, a]]", "non-number");
    expectError("name: x\nspacing: 3\nelements: [[0, 0]]", "unknown key 'spacing'");
    EXPECT_THROW(AntennaArray::fromYamlFile("/nonexistent/array.yaml"), std::runtime_error);
}

TEST(ArrayGeometry, LinearDetectionAndMirror)
{
    const AntennaArray r = test::loadArray("rt-ac86u");
    EXPECT_TRUE(r.isLinear());
    EXPECT_NEAR(r.axisDirection(), M_PI / 2, 1e-12);
    EXPECT_NEAR(r.broadside(), 0.0, 1e-12);
    // Along y: θ and 180° − θ give the same CSI.
    const double theta = 0.4;
    EXPECT_NEAR(r.mirrorOf(theta), M_PI - theta, 1e-12);
    for (size_t i = 0; i < r.size(); ++i)
        EXPECT_NEAR(
            r.steeringPhase(i, theta, 5.775e9), r.steeringPhase(i, r.mirrorOf(theta), 5.775e9),
            1e-9);
    const auto [lo, hi] = r.searchInterval();
    EXPECT_NEAR(lo, -M_PI / 2, 1e-12);
    EXPECT_NEAR(hi, M_PI / 2, 1e-12);

    const AntennaArray sq = test::loadArray("square-2x2");
    EXPECT_FALSE(sq.isLinear());
    EXPECT_NEAR(sq.mirrorOf(theta), theta, 1e-12);
    EXPECT_NEAR(sq.searchInterval().second - sq.searchInterval().first, 2 * M_PI, 1e-12);
    // A 2-D array does tell θ from its mirror.
    double diff = 0;
    for (size_t i = 0; i < sq.size(); ++i)
        diff += std::abs(
            sq.steeringPhase(i, theta, 5.775e9) - sq.steeringPhase(i, M_PI - theta, 5.775e9));
    EXPECT_GT(diff, 0.1);
    // Two elements are always a line; a tilted line has its own broadside.
    AntennaArray tilted;
    tilted.name = "tilted";
    tilted.elements = {{0, 0}, {0.02, 0.02}, {0.04, 0.04}};
    EXPECT_TRUE(tilted.isLinear());
    EXPECT_NEAR(tilted.axisDirection(), M_PI / 4, 1e-12);
    EXPECT_NEAR(tilted.broadside(), -M_PI / 4, 1e-12);
}

TEST(ArraySteering, SignConventionAndPerSubcarrierFrequency)
{
    AntennaArray a;
    a.name = "pair";
    a.elements = {{0, 0}, {0.05, 0}};
    // Source straight ahead (+x): element 1 is 5 cm closer, so its phase leads by 2π·0.05/λ.
    const double f = 5.8e9;
    const Eigen::VectorXcd v = a.steeringVector(0.0, f);
    EXPECT_NEAR(
        std::arg(v[1] * std::conj(v[0])),
        std::remainder(2 * M_PI * f * 0.05 / kSpeedOfLightMps, 2 * M_PI), 1e-9);
    // Wideband: one column per frequency, each with its own wavelength.
    const Eigen::MatrixXcd W = a.wideband(0.0, {5.7e9, 5.8e9});
    EXPECT_NEAR(
        std::arg(W(1, 0)), std::remainder(2 * M_PI * 5.7e9 * 0.05 / kSpeedOfLightMps, 2 * M_PI),
        1e-9);
    EXPECT_NEAR(
        std::arg(W(1, 1)), std::remainder(2 * M_PI * 5.8e9 * 0.05 / kSpeedOfLightMps, 2 * M_PI),
        1e-9);
}

TEST(ArrayCrb, MatchesTheDesignFigure)
{
    // DESIGN.md §5: one path, 4 antennas at λ/2, 234 subcarriers, 20 dB: 0.04°.
    const double f = 5.775e9, lambda = kSpeedOfLightMps / f;
    AntennaArray ula;
    ula.name = "ula";
    for (int i = 0; i < 4; ++i) ula.elements.emplace_back(0.0, i * lambda / 2);
    const std::vector<double> freqs(234, f);
    const double crb = ula.aoaCramerRaoBound(0.0, freqs, 100.0) * 180 / M_PI;
    EXPECT_NEAR(crb, 0.038, 0.003);
    // More snapshots, smaller bound (∝ 1/√N); off broadside, larger.
    EXPECT_NEAR(ula.aoaCramerRaoBound(0.0, freqs, 100.0, 4) * 180 / M_PI, crb / 2, 1e-6);
    EXPECT_GT(ula.aoaCramerRaoBound(1.2, freqs, 100.0), ula.aoaCramerRaoBound(0.0, freqs, 100.0));
}
