#include <gtest/gtest.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>

#include <algorithm>

#include "SyntheticCsi.h"

using namespace mrpt_wifi;
using namespace std::chrono_literals;

namespace
{
struct Harness
{
    explicit Harness(CsiFrameAssemblerOptions o = {})
        : assembler(o, [this](CObservationWiFiCSI::Ptr&& f) { frames.push_back(std::move(f)); })
    {
    }
    void push(const std::vector<uint8_t>& d, mrpt::Clock::time_point t)
    {
        assembler.push(d.data(), d.size(), t, "10.10.10.10");
    }
    void pushAll(const std::vector<std::vector<uint8_t>>& ds, mrpt::Clock::time_point t)
    {
        for (const auto& d : ds) push(d, t);
    }
    std::vector<CObservationWiFiCSI::Ptr> frames;
    CsiFrameAssembler assembler;
};

const auto t0 = mrpt::Clock::fromDouble(1000.0);

CsiFrameAssemblerOptions keepBins()
{
    CsiFrameAssemblerOptions o;
    o.overwrittenBins = OverwrittenBinPolicy::Keep;
    return o;
}
}  // namespace

TEST(CsiFrameAssembler, EmitsACompleteFrameOnItsLastDatagram)
{
    Harness h(keepBins());
    // The first frame teaches how many streams the transmitter sends: it goes out when the
    // next one starts. From then on a frame goes out on its last datagram.
    h.pushAll(
        nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 6)),
        t0 - std::chrono::milliseconds(10));
    EXPECT_TRUE(h.frames.empty());
    const auto truth = test::syntheticFrame(4, 4, 80, 7);
    const auto datagrams = nexmon::encodeFrame(*truth);
    ASSERT_EQ(datagrams.size(), 16u);
    for (size_t i = 0; i < datagrams.size(); ++i)
    {
        h.push(datagrams[i], t0 + std::chrono::microseconds(i));
        if (i + 1 < datagrams.size())
        {
            EXPECT_EQ(h.frames.size(), 1u) << "emitted at datagram " << i;
        }
    }
    // No extra frame of latency (WiROS waits for the next frame).
    ASSERT_EQ(h.frames.size(), 2u);
    EXPECT_TRUE(h.frames[0]->isComplete());
    const auto& f = *h.frames[1];
    EXPECT_TRUE(f.isComplete());
    EXPECT_EQ(f.nTx, 4);
    EXPECT_EQ(f.nRx, 4);
    EXPECT_EQ(f.sequenceNumber, 7);
    EXPECT_EQ(f.rssi_dBm, -48);
    EXPECT_EQ(f.routerAddress, "10.10.10.10");
    EXPECT_EQ(f.timestamp, t0);  // arrival of the first datagram
    for (unsigned tx = 0; tx < 4; ++tx)
        for (unsigned rx = 0; rx < 4; ++rx)
            for (unsigned b = 0; b < 256; ++b)
                ASSERT_NEAR(
                    std::abs(f.at(tx, rx, b) - truth->at(tx, rx, b)), 0.0f,
                    std::abs(truth->at(tx, rx, b)) / 1024.0f);
    EXPECT_EQ(h.assembler.stats().framesComplete, 2u);
    EXPECT_EQ(h.assembler.pendingFrames(), 0u);
}

TEST(CsiFrameAssembler, StreamMajorOrderDoesNotCutTheFirstFrameShort)
{
    // Datagrams stream by stream (cores 0..3 of stream 0 first): after four of them the frame
    // looks complete for a one-stream transmitter. It must still come out as 4x4.
    Harness h;
    for (uint16_t seq = 30; seq < 33; ++seq)
    {
        const auto coreMajor = nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, seq));
        for (unsigned stream = 0; stream < 4; ++stream)
            for (unsigned core = 0; core < 4; ++core) h.push(coreMajor[core * 4 + stream], t0);
    }
    h.assembler.flushAll();
    ASSERT_EQ(h.frames.size(), 3u);
    for (const auto& f : h.frames)
    {
        EXPECT_EQ(f->nTx, 4);
        EXPECT_TRUE(f->isComplete());
    }
    EXPECT_EQ(h.assembler.stats().lateDatagrams, 0u);
    EXPECT_EQ(h.assembler.stats().framesComplete, 3u);
}

TEST(CsiFrameAssembler, IncompleteFrameEmittedWhenTheNextStarts)
{
    Harness h;
    auto first = nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 10));
    first.erase(first.begin() + 5);  // one pair lost
    h.pushAll(first, t0);
    EXPECT_TRUE(h.frames.empty());
    const auto second = nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 11));
    h.push(second[0], t0 + 10ms);
    ASSERT_EQ(h.frames.size(), 1u);
    EXPECT_EQ(h.frames[0]->sequenceNumber, 10);
    EXPECT_EQ(h.frames[0]->presentPairs(), 15u);
    EXPECT_FALSE(h.frames[0]->isPresent(1, 1));  // datagram 5 = core 1, stream 1
    EXPECT_EQ(h.assembler.stats().framesIncomplete, 1u);
    EXPECT_EQ(h.assembler.stats().missingPairs, 1u);
}

TEST(CsiFrameAssembler, TimeoutEmitsAStalledFrame)
{
    CsiFrameAssemblerOptions o;
    o.frameTimeout_s = 0.05;
    Harness h(o);
    h.pushAll(nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 2)), t0 - 1ms);
    auto ds = nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 3));
    ds.resize(10);
    h.pushAll(ds, t0);
    ASSERT_EQ(h.frames.size(), 1u);  // frame 2, when frame 3 started
    h.assembler.flushExpired(t0 + 40ms);
    EXPECT_EQ(h.frames.size(), 1u);
    h.assembler.flushExpired(t0 + 60ms);
    ASSERT_EQ(h.frames.size(), 2u);
    EXPECT_EQ(h.assembler.stats().missingPairs, 6u);
}

TEST(CsiFrameAssembler, CountsDuplicatesAndLateDatagramsAndKeepsRetries)
{
    Harness h;
    // A whole frame first: the transmitter's shape (4 streams x 4 cores) is known.
    h.pushAll(nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 19)), t0 - 1ms);
    const auto a = nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 20));
    const auto b = nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 21));
    h.push(a[0], t0);
    h.push(a[0], t0);        // duplicated on the wire: the same words
    h.push(b[0], t0 + 1ms);  // frame 21 starts: frame 20 goes out incomplete
    h.push(a[1], t0 + 2ms);  // reordered: frame 20 is gone
    for (size_t i = 1; i < b.size(); ++i) h.push(b[i], t0 + 3ms);
    ASSERT_EQ(h.frames.size(), 3u);
    EXPECT_EQ(h.frames[2]->sequenceNumber, 21);
    EXPECT_TRUE(h.frames[2]->isComplete());
    const auto& s = h.assembler.stats();
    EXPECT_EQ(s.duplicates, 1u);
    EXPECT_EQ(s.lateDatagrams, 1u);
    EXPECT_EQ(s.framesComplete, 2u);
    EXPECT_EQ(s.framesIncomplete, 1u);
    EXPECT_EQ(s.retries, 0u);
    // A copy of a datagram of a frame already emitted is a duplicate, not a new frame.
    h.push(b[3], t0 + 4ms);
    EXPECT_EQ(h.frames.size(), 3u);
    EXPECT_EQ(h.assembler.stats().duplicates, 2u);

    // An 802.11 retry: frame 21 received again, other CSI. Another measurement: kept whole.
    auto again = test::syntheticFrame(4, 4, 80, 21);
    for (auto& v : again->csi) v *= std::complex<float>(0.0f, 1.0f);
    const auto retry = nexmon::encodeFrame(*again);
    for (const auto& d : retry) h.push(d, t0 + 5ms);
    ASSERT_EQ(h.frames.size(), 4u);
    EXPECT_EQ(h.frames[3]->sequenceNumber, 21);
    EXPECT_TRUE(h.frames[3]->isComplete());
    EXPECT_NEAR(
        std::abs(h.frames[3]->at(1, 2, 40) - again->at(1, 2, 40)), 0.0f,
        std::abs(again->at(1, 2, 40)) / 1024.0f);
    EXPECT_EQ(h.assembler.stats().retries, 1u);
    EXPECT_EQ(h.assembler.stats().lateDatagrams, 1u);
}

TEST(CsiFrameAssembler, LateFrameIsAssembledAndKept)
{
    // Frame 1933 arrives after 1934 has started (reordered on the way): both come out whole.
    Harness h;
    h.pushAll(nexmon::encodeFrame(*test::syntheticFrame(1, 4, 20, 1932)), t0);
    const auto newer = nexmon::encodeFrame(*test::syntheticFrame(1, 4, 20, 1934));
    const auto older = nexmon::encodeFrame(*test::syntheticFrame(1, 4, 20, 1933));
    h.push(newer[0], t0 + 1ms);
    for (const auto& d : older) h.push(d, t0 + 2ms);
    for (size_t i = 1; i < newer.size(); ++i) h.push(newer[i], t0 + 3ms);
    h.assembler.flushAll();
    ASSERT_EQ(h.frames.size(), 3u);
    std::vector<uint16_t> seqs;
    for (const auto& f : h.frames)
    {
        EXPECT_TRUE(f->isComplete()) << f->sequenceNumber;
        seqs.push_back(f->sequenceNumber);
    }
    std::sort(seqs.begin(), seqs.end());
    EXPECT_EQ(seqs, (std::vector<uint16_t>{1932, 1933, 1934}));
    EXPECT_EQ(h.assembler.stats().lateFrames, 1u);
    EXPECT_EQ(h.assembler.stats().lateDatagrams, 0u);
    EXPECT_EQ(h.assembler.stats().framesIncomplete, 0u);
}

TEST(CsiFrameAssembler, RouterReportingSomeCoresGivesCompleteFramesOfThoseCores)
{
    // An RT-AC86U with makecsiparams -C 0xb: cores 0, 1, 3 only. Frames are complete, hold
    // three rows and say which cores they are.
    Harness h(keepBins());
    std::vector<CObservationWiFiCSI::Ptr> sent;
    for (uint16_t seq = 50; seq < 54; ++seq)
    {
        sent.push_back(test::syntheticFrame(1, 4, 20, seq));
        for (const auto& d : nexmon::encodeFrame(*sent.back()))
        {
            nexmon::DatagramHeader hd;
            nexmon::RejectReason why{};
            ASSERT_TRUE(nexmon::parseHeader(d.data(), d.size(), nexmon::FormatHint::Auto, hd, why));
            if (hd.core != 2) h.push(d, t0);
        }
    }
    h.assembler.flushAll();
    ASSERT_EQ(h.frames.size(), 4u);
    for (size_t i = 0; i < 4; ++i)
    {
        const auto& f = *h.frames[i];
        EXPECT_TRUE(f.isComplete());
        EXPECT_EQ(f.nRx, 3);
        EXPECT_EQ(f.rxCores, (std::vector<uint8_t>{0, 1, 3}));
        EXPECT_NEAR(
            std::abs(f.at(0, 2, 20) - sent[i]->at(0, 3, 20)), 0.0f,
            std::abs(sent[i]->at(0, 3, 20)) / 1024.0f);
    }
    const auto& s = h.assembler.stats();
    EXPECT_EQ(s.framesComplete, 4u);
    EXPECT_EQ(s.framesIncomplete, 0u);
    EXPECT_EQ(s.coresSeen, 0x0b);
    EXPECT_NE(s.asString().find("on receive cores 0, 1, 3"), std::string::npos) << s.asString();
    // Written back out, the datagrams carry their own cores again.
    for (const auto& d : nexmon::encodeFrame(*h.frames[0]))
    {
        nexmon::DatagramHeader hd;
        nexmon::RejectReason why{};
        ASSERT_TRUE(nexmon::parseHeader(d.data(), d.size(), nexmon::FormatHint::Auto, hd, why));
        EXPECT_NE(hd.core, 2);
    }
}

TEST(CsiFrameAssembler, LearnsHowManyStreamsATransmitterSends)
{
    Harness h;
    const char *client = "02:00:00:00:00:01", *ap = "02:00:00:00:00:02";
    // A one-stream client: once learnt, complete after its four cores.
    h.pushAll(nexmon::encodeFrame(*test::syntheticFrame(1, 4, 80, 1, client)), t0);
    h.pushAll(nexmon::encodeFrame(*test::syntheticFrame(1, 4, 80, 2, client)), t0);
    ASSERT_EQ(h.frames.size(), 2u);
    EXPECT_EQ(h.frames[1]->nTx, 1);
    EXPECT_TRUE(h.frames[1]->isComplete());
    // A four-stream AP: its frames grow as streams appear.
    h.pushAll(nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 1, ap)), t0);
    h.pushAll(nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 2, ap)), t0);
    ASSERT_EQ(h.frames.size(), 4u);
    EXPECT_EQ(h.frames[3]->nTx, 4);
    EXPECT_TRUE(h.frames[3]->isComplete());
    EXPECT_EQ(h.assembler.stats().framesIncomplete, 0u);
}

TEST(CsiFrameAssembler, InterleavedTransmittersAndGarbage)
{
    Harness h;
    const auto a = nexmon::encodeFrame(*test::syntheticFrame(2, 4, 40, 5, "02:00:00:00:00:0a"));
    const auto b = nexmon::encodeFrame(*test::syntheticFrame(2, 4, 20, 9, "02:00:00:00:00:0b"));
    const std::vector<uint8_t> junk = {0x11, 0x11, 1, 2, 3};
    for (size_t i = 0; i < a.size(); ++i)
    {
        h.push(a[i], t0);
        h.push(junk, t0);
        h.push(b[i], t0);
    }
    h.assembler.flushAll();
    ASSERT_EQ(h.frames.size(), 2u);
    std::sort(
        h.frames.begin(), h.frames.end(),
        [](const auto& x, const auto& y) { return x->transmitter < y->transmitter; });
    EXPECT_EQ(h.frames[0]->transmitter.asString(), "02:00:00:00:00:0a");
    EXPECT_EQ(h.frames[0]->nfft(), 128u);
    EXPECT_EQ(h.frames[1]->nfft(), 64u);
    EXPECT_EQ(h.assembler.stats().rejected[size_t(nexmon::RejectReason::TooShort)], 8u);
    EXPECT_EQ(h.assembler.stats().accepted, 16u);
}

TEST(CsiFrameAssembler, CoreMaskRejectsUnexpectedCores)
{
    CsiFrameAssemblerOptions o;
    o.coreMask = 0x03;  // makecsiparams -C 0x3
    Harness h(o);
    h.pushAll(nexmon::encodeFrame(*test::syntheticFrame(1, 4, 80, 1)), t0);
    h.assembler.flushAll();
    ASSERT_EQ(h.frames.size(), 1u);
    EXPECT_EQ(h.frames[0]->nRx, 2);
    EXPECT_TRUE(h.frames[0]->isComplete());
    EXPECT_EQ(h.assembler.stats().rejected[size_t(nexmon::RejectReason::BadCoreStream)], 2u);
}

TEST(CsiFrameAssembler, BoundedNumberOfTrackedTransmitters)
{
    CsiFrameAssemblerOptions o;
    o.maxPendingTransmitters = 4;
    Harness h(o);
    for (int i = 0; i < 50; ++i)
    {
        char mac[18];
        std::snprintf(mac, sizeof(mac), "02:00:00:00:01:%02x", i);
        h.push(
            nexmon::encodeFrame(*test::syntheticFrame(1, 4, 80, 1, mac))[0],
            t0 + std::chrono::milliseconds(i));
        EXPECT_LE(h.assembler.pendingFrames(), 4u);
    }
    h.assembler.flushAll();
    EXPECT_EQ(h.frames.size(), 50u);
}

TEST(OverwrittenBins, RepairInterpolatesDataSubcarrierAndMasksTheRest)
{
    auto f = test::syntheticFrame(1, 1, 80);
    const unsigned n = 256;
    auto& km2 = f->at(0, 0, subcarrierToBin(-2, n));
    auto& kp3 = f->at(0, 0, subcarrierToBin(3, n));
    km2 = {10.0f, 0.0f};
    kp3 = {0.0f, 20.0f};
    f->at(0, 0, subcarrierToBin(2, n)) = {999.0f, 999.0f};  // PHY status garbage
    applyOverwrittenBinPolicy(*f, OverwrittenBinPolicy::Repair);
    // k = 2 lies 4/5 of the way from k = -2 to k = 3.
    const auto repaired = f->at(0, 0, subcarrierToBin(2, n));
    EXPECT_NEAR(repaired.real(), 2.0f, 1e-5f);
    EXPECT_NEAR(repaired.imag(), 16.0f, 1e-5f);
    EXPECT_EQ(f->at(0, 0, subcarrierToBin(0, n)), std::complex<float>(0, 0));
    EXPECT_EQ(f->maskedBins, (std::vector<uint16_t>{128, 129}));

    auto g = test::syntheticFrame(1, 1, 80);
    applyOverwrittenBinPolicy(*g, OverwrittenBinPolicy::Mask);
    EXPECT_EQ(g->maskedBins, (std::vector<uint16_t>{128, 129, 130}));
    EXPECT_EQ(g->at(0, 0, 130), std::complex<float>(0, 0));

    // 20 MHz: k = 28 is the band edge; extrapolated from k = 26, 27.
    auto e = test::syntheticFrame(1, 1, 20);
    e->at(0, 0, subcarrierToBin(26, 64)) = {1.0f, 0.0f};
    e->at(0, 0, subcarrierToBin(27, 64)) = {2.0f, 0.0f};
    applyOverwrittenBinPolicy(*e, OverwrittenBinPolicy::Repair);
    EXPECT_NEAR(e->at(0, 0, subcarrierToBin(28, 64)).real(), 3.0f, 1e-5f);
    EXPECT_EQ(e->maskedBins, (std::vector<uint16_t>{61, 62}));

    auto k = test::syntheticFrame(1, 1, 80);
    const auto before = k->csi;
    applyOverwrittenBinPolicy(*k, OverwrittenBinPolicy::Keep);
    EXPECT_EQ(k->csi, before);
    EXPECT_THROW(overwrittenBinPolicyFromString("fix"), std::invalid_argument);
}

TEST(CsiFrameAssembler, CoreMaskChangingWithinAFrameIsRejectedNotWrittenOutOfBounds)
{
    // Regression (libFuzzer): a UbiLocate frame whose first datagram announces two cores and a
    // later one (same sequence) announces four and carries core 3.
    Harness h;
    auto frame =
        test::syntheticFrame(1, 4, 80, 9, "02:00:00:00:00:0c", NexmonHeaderVariant::UbiLocate);
    auto first = nexmon::headerFor(*frame, 0, 0);
    first.coreMask = 0x03;
    std::vector<uint8_t> d0, d3;
    nexmon::encodeDatagram(first, frame->pair(0, 0), d0);
    nexmon::encodeDatagram(nexmon::headerFor(*frame, 0, 3), frame->pair(0, 3), d3);
    h.push(d0, t0);
    h.push(d3, t0);
    h.assembler.flushAll();
    ASSERT_EQ(h.frames.size(), 1u);
    EXPECT_EQ(h.frames[0]->nRx, 2);
    EXPECT_EQ(h.assembler.stats().rejected[size_t(nexmon::RejectReason::BadCoreStream)], 1u);
}
