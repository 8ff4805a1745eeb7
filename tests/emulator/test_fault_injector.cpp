// Fault injection: exact behaviour per fault, corruption the decoder must reject, seeds.
#include <gtest/gtest.h>
#include <mrpt_wifi/emulator/FaultInjector.h>
#include <mrpt_wifi/sensor/NexmonFormat.h>

#include "SyntheticCsi.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::emulator;

namespace
{
/** Distinct datagrams: a real 80 MHz encoding with the index in the sequence number. */
std::vector<std::vector<uint8_t>> stream(
    size_t n, NexmonHeaderVariant v = NexmonHeaderVariant::Nexmon)
{
    std::vector<std::vector<uint8_t>> out;
    for (size_t i = 0; i < n; ++i)
    {
        auto frame = test::syntheticFrame(1, 1, 80, uint16_t(i), "02:00:00:00:00:01", v);
        out.push_back(nexmon::encodeFrame(*frame).front());
    }
    return out;
}

std::vector<std::vector<uint8_t>> run(FaultInjector& f, const std::vector<std::vector<uint8_t>>& in)
{
    std::vector<std::vector<uint8_t>> out;
    auto sink = [&](const std::vector<uint8_t>& d) { out.push_back(d); };
    for (size_t i = 0; i < in.size(); ++i) f.submit(in[i], 0.001 * double(i), sink);
    f.flush(sink);
    return out;
}

uint16_t seqOf(const std::vector<uint8_t>& d)
{
    return uint16_t((d[10] | d[11] << 8) >> 4);
}
}  // namespace

TEST(EmulatorFaults, NoFaultsIsTheIdentity)
{
    FaultInjector f(3);
    const auto in = stream(50);
    EXPECT_EQ(run(f, in), in);
    EXPECT_EQ(f.counters().submitted, 50u);
}

TEST(EmulatorFaults, LossDuplicationCountsMatchTheOutput)
{
    FaultSettings s;
    s.loss = 0.2;
    s.duplicate = 0.1;
    FaultInjector f(42, s);
    const auto in = stream(2000);
    const auto out = run(f, in);
    const auto& c = f.counters();
    EXPECT_EQ(out.size(), in.size() - c.lost + c.duplicated);
    EXPECT_NEAR(double(c.lost) / 2000, 0.2, 0.04);
    EXPECT_NEAR(double(c.duplicated) / (2000 - c.lost), 0.1, 0.03);
    // Duplicates are adjacent copies; order is kept.
    size_t copies = 0;
    for (size_t i = 1; i < out.size(); ++i)
    {
        if (out[i] == out[i - 1]) ++copies;
        EXPECT_LE(seqOf(out[i - 1]), seqOf(out[i]));
    }
    EXPECT_EQ(copies, c.duplicated);
}

TEST(EmulatorFaults, ReorderSwapsWithTheNextDatagram)
{
    FaultSettings s;
    s.reorder = 0.15;
    FaultInjector f(7, s);
    const auto out = run(f, stream(1000));
    ASSERT_EQ(out.size(), 1000u);
    size_t descents = 0;
    for (size_t i = 1; i < out.size(); ++i)
        if (seqOf(out[i]) < seqOf(out[i - 1]))
        {
            ++descents;
            EXPECT_EQ(seqOf(out[i - 1]), seqOf(out[i]) + 1);  // adjacent swap only
        }
    EXPECT_EQ(descents, f.counters().reordered);
    EXPECT_GT(descents, 50u);
    EXPECT_LE(f.counters().reorderExpired, 1u);  // only a held last one
}

TEST(EmulatorFaults, HeldDatagramIsSentAloneAfterTheHoldLimit)
{
    FaultSettings s;
    s.reorder = 1.0;
    FaultInjector f(1, s);
    std::vector<std::vector<uint8_t>> out;
    auto sink = [&](const std::vector<uint8_t>& d) { out.push_back(d); };
    const auto in = stream(2);
    f.submit(in[0], 0.0, sink);
    EXPECT_TRUE(out.empty());
    f.releaseExpired(0.01, sink);
    EXPECT_TRUE(out.empty());
    f.releaseExpired(0.2, sink);
    ASSERT_EQ(out.size(), 1u);
    EXPECT_EQ(f.counters().reorderExpired, 1u);
    EXPECT_EQ(f.counters().reordered, 0u);
}

TEST(EmulatorFaults, EveryCorruptionIsRejectedByTheDecoderInEveryVariant)
{
    for (auto v :
         {NexmonHeaderVariant::Nexmon, NexmonHeaderVariant::NexmonLegacy,
          NexmonHeaderVariant::UbiLocate})
    {
        FaultSettings s;
        s.corrupt = 1.0;
        FaultInjector f(11, s);
        const auto out = run(f, stream(600, v));
        ASSERT_EQ(out.size(), 600u);
        for (const auto& d : out)
        {
            nexmon::DatagramHeader h;
            nexmon::RejectReason why;
            EXPECT_FALSE(nexmon::parseHeader(d.data(), d.size(), nexmon::FormatHint::Auto, h, why))
                << toString(v);
        }
        const auto& c = f.counters();
        EXPECT_EQ(c.corruptedTotal(), 600u);
        EXPECT_EQ(c.corruptedSent, 600u);
        for (auto n : c.corrupted) EXPECT_GT(n, 120u);  // all three kinds occur
    }
}

TEST(EmulatorFaults, SameSeedSameOutputOtherSeedOther)
{
    FaultSettings s;
    s.loss = 0.1;
    s.duplicate = 0.1;
    s.reorder = 0.1;
    s.corrupt = 0.1;
    const auto in = stream(500);
    FaultInjector a(99, s), b(99, s), c(100, s);
    const auto outA = run(a, in);
    EXPECT_EQ(outA, run(b, in));
    EXPECT_NE(outA, run(c, in));
    EXPECT_EQ(a.counters().toJson(), b.counters().toJson());
}

TEST(EmulatorFaults, SettingsAreValidated)
{
    FaultSettings s;
    s.loss = 1.5;
    EXPECT_THROW(FaultInjector(1, s), std::invalid_argument);
    s.loss = 0;
    s.reorder = -0.1;
    EXPECT_THROW(s.validate(), std::invalid_argument);
    s.reorder = 0;
    s.silenceRate_Hz = -1;
    EXPECT_THROW(s.validate(), std::invalid_argument);
}

TEST(EmulatorFaults, SilenceEpisodesFollowTheirRate)
{
    FaultSettings s;
    s.silenceRate_Hz = 2.0;
    FaultInjector f(5, s);
    unsigned starts = 0;
    for (int i = 0; i < 10000; ++i) starts += f.silenceStarts(0.01);  // 100 s
    EXPECT_NEAR(starts, 200, 45);
    EXPECT_EQ(f.counters().silences, starts);
}
