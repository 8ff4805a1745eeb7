#include <gtest/gtest.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sensor/CsiFrameAssembler.h>

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
    const auto truth = test::syntheticFrame(4, 4, 80, 7);
    const auto datagrams = nexmon::encodeFrame(*truth);
    ASSERT_EQ(datagrams.size(), 16u);
    for (size_t i = 0; i < datagrams.size(); ++i)
    {
        EXPECT_TRUE(h.frames.empty()) << "emitted before datagram " << i;
        h.push(datagrams[i], t0 + std::chrono::microseconds(i));
    }
    // No extra frame of latency (WiROS waits for the next frame).
    ASSERT_EQ(h.frames.size(), 1u);
    const auto& f = *h.frames[0];
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
    EXPECT_EQ(h.assembler.stats().framesComplete, 1u);
    EXPECT_EQ(h.assembler.pendingFrames(), 0u);
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
    auto ds = nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 3));
    ds.resize(10);
    h.pushAll(ds, t0);
    h.assembler.flushExpired(t0 + 40ms);
    EXPECT_TRUE(h.frames.empty());
    h.assembler.flushExpired(t0 + 60ms);
    ASSERT_EQ(h.frames.size(), 1u);
    EXPECT_EQ(h.assembler.stats().missingPairs, 6u);
}

TEST(CsiFrameAssembler, CountsDuplicatesAndLateDatagrams)
{
    Harness h;
    const auto a = nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 20));
    const auto b = nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 21));
    h.push(a[0], t0);
    h.push(a[0], t0);        // duplicated on the wire
    h.push(b[0], t0 + 1ms);  // frame 21 starts: frame 20 goes out incomplete
    h.push(a[1], t0 + 2ms);  // reordered: frame 20 is gone
    for (size_t i = 1; i < b.size(); ++i) h.push(b[i], t0 + 3ms);
    ASSERT_EQ(h.frames.size(), 2u);
    EXPECT_EQ(h.frames[1]->sequenceNumber, 21);
    EXPECT_TRUE(h.frames[1]->isComplete());
    const auto& s = h.assembler.stats();
    EXPECT_EQ(s.duplicates, 1u);
    EXPECT_EQ(s.lateDatagrams, 1u);
    EXPECT_EQ(s.framesComplete, 1u);
    EXPECT_EQ(s.framesIncomplete, 1u);
    // A late copy of a frame already emitted complete is late too, not a new frame.
    h.push(b[3], t0 + 4ms);
    EXPECT_EQ(h.frames.size(), 2u);
    EXPECT_EQ(h.assembler.stats().lateDatagrams, 2u);
}

TEST(CsiFrameAssembler, LearnsHowManyStreamsATransmitterSends)
{
    Harness h;
    // A one-stream client: complete after its four cores, no waiting for streams 1..3.
    h.pushAll(nexmon::encodeFrame(*test::syntheticFrame(1, 4, 80, 1, "02:00:00:00:00:01")), t0);
    ASSERT_EQ(h.frames.size(), 1u);
    EXPECT_EQ(h.frames[0]->nTx, 1);
    EXPECT_TRUE(h.frames[0]->isComplete());
    // A four-stream AP: its first frame grows as streams appear, then completes.
    h.pushAll(nexmon::encodeFrame(*test::syntheticFrame(4, 4, 80, 1, "02:00:00:00:00:02")), t0);
    ASSERT_EQ(h.frames.size(), 2u);
    EXPECT_EQ(h.frames[1]->nTx, 4);
    EXPECT_TRUE(h.frames[1]->isComplete());
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
    ASSERT_EQ(h.frames.size(), 2u);
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
