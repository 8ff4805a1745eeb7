/* The sub-band sign quirk on real RT-AC86U captures (../shared/data/real): the preprocessing
 * removes the ~180° phase step between k = −65 and k = −64 that every frame shows. */
#include <gtest/gtest.h>
#include <mrpt_wifi/obs/CsiPreprocessing.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>

#include <algorithm>

#include "SyntheticCsi.h"
#include "TestSupport.h"

using namespace mrpt_wifi;

TEST(PreprocessSign, RealCapturesLoseTheir180DegreeStep)
{
    MRPT_WIFI_REQUIRE_REAL_CAPTURE(path, "ubilocate_4x4_80mhz.pcap");
    std::vector<CObservationWiFiCSI::Ptr> frames;
    readCsiFrames(path, {}, [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(f); });
    ASSERT_EQ(frames.size(), 9u);
    const AntennaArray rx = test::loadArray("rt-ac86u");
    PreprocessOptions off;
    off.correctSubbandSign80 = false;
    off.removeSamplingTimeOffset = false;
    PreprocessOptions on = off;
    on.correctSubbandSign80 = true;
    CsiPreprocessor withFix(on, rx), without(off, rx);
    // Phase step between k = −65 and −64 against the median neighbour step, per row.
    const auto stepAt65 = [](const CleanCsi& f, Eigen::Index row)
    {
        const auto& k = f.layout->subcarriers;
        const size_t j = size_t(std::find(k.begin(), k.end(), -65) - k.begin());
        std::vector<double> steps;
        for (size_t q = 0; q + 1 < k.size(); ++q)
            if (k[q + 1] - k[q] == 1 && k[q] != -65)
                steps.push_back(
                    std::arg(f.H(row, Eigen::Index(q + 1)) * std::conj(f.H(row, Eigen::Index(q)))));
        std::nth_element(steps.begin(), steps.begin() + long(steps.size() / 2), steps.end());
        const double s =
            std::arg(f.H(row, Eigen::Index(j + 1)) * std::conj(f.H(row, Eigen::Index(j))));
        return std::abs(std::remainder(s - steps[steps.size() / 2], 2 * M_PI)) * 180 / M_PI;
    };
    CleanCsi a, b;
    for (const auto& f : frames)
    {
        ASSERT_EQ(without.process(*f, a), RejectReason::Accepted);
        ASSERT_EQ(withFix.process(*f, b), RejectReason::Accepted);
        ASSERT_EQ(a.nTx, 4u);
        for (Eigen::Index row = 0; row < a.H.rows(); ++row)
        {
            EXPECT_GT(stepAt65(a, row), 150.0) << "seq " << f->sequenceNumber << " row " << row;
            EXPECT_LT(stepAt65(b, row), 30.0) << "seq " << f->sequenceNumber << " row " << row;
        }
    }
}

TEST(PreprocessSto, RealCapturesHaveNoSlopeLeftInAnyStream)
{
    // Each 802.11ac stream carries its own cyclic shift delay: the linear phase is fitted per
    // stream. Afterwards every row's median neighbour step is close to zero.
    MRPT_WIFI_REQUIRE_REAL_CAPTURE(path, "ubilocate_4x4_80mhz.pcap");
    std::vector<CObservationWiFiCSI::Ptr> frames;
    readCsiFrames(path, {}, [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(f); });
    CsiPreprocessor pre({}, test::loadArray("rt-ac86u"));
    CleanCsi c;
    for (const auto& f : frames)
    {
        ASSERT_EQ(pre.process(*f, c), RejectReason::Accepted);
        const auto& k = c.layout->subcarriers;
        for (Eigen::Index row = 0; row < c.H.rows(); ++row)
        {
            std::vector<double> steps;
            for (size_t j = 0; j + 1 < k.size(); ++j)
                if (k[j + 1] - k[j] == 1)
                    steps.push_back(std::arg(
                        c.H(row, Eigen::Index(j + 1)) * std::conj(c.H(row, Eigen::Index(j)))));
            std::nth_element(steps.begin(), steps.begin() + long(steps.size() / 2), steps.end());
            EXPECT_LT(std::abs(steps[steps.size() / 2]), 0.05)
                << "seq " << f->sequenceNumber << " row " << row;
        }
    }
}
