/* The receive chains' jump states (issue 21): detection on simulated frames with known states
 * and on real captures without jumps, the calibration file's states, online learning of a state
 * the calibration lacks, and bearings through jumps against the same rooms without them. */
#include <gtest/gtest.h>
#include <mrpt_wifi/obs/ChainStateRecorder.h>
#include <mrpt_wifi/obs/ChainStates.h>
#include <mrpt_wifi/sensor/CsiFileReader.h>

#include <fstream>
#include <map>
#include <optional>
#include <set>

#include "BearingAccuracy.h"
#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::test;

namespace
{
/** A random room with the jump states on (3 states, 3 ns apart, each with its own phase). */
sim::Scenario jumpyRoom(uint32_t seed, double rate_Hz, double duration_s)
{
    sim::RandomRoomOptions ro;
    ro.arraysDir = std::string(MRPT_WIFI_SOURCE_DIR) + "/share/arrays";
    ro.duration_s = duration_s;
    sim::Scenario sc = sim::randomRoomScenario(seed, ro);
    sc.impairments.antennaJumps = rate_Hz > 0;
    sc.impairments.jumpStates = 3;
    sc.impairments.jumpStep_s = 3e-9;
    sc.impairments.jumpRate_Hz = rate_Hz;
    sc.impairments.jumpStatePhase = true;
    return sc;
}

struct Detection
{
    size_t frames = 0, agree = 0, unknown = 0;
    uint64_t trueChanges = 0, detectedChanges = 0;
    double maxDeviation_ns = 0;  //!< of a frame's delay from its true state's mean delay
};

/** Streams a room through an uncalibrated preprocessor and compares the tracker's states with
 *  the simulator's, chain by chain (tracker ids mapped to true states by majority). */
Detection detect(const sim::Scenario& sc)
{
    sim::Simulator simulator(sc);
    PreprocessOptions po;
    po.trackChainStates = true;
    CsiPreprocessor pre(po, fromSimArray(sc.receiver.array));
    std::vector<std::pair<std::vector<uint8_t>, std::vector<uint8_t>>> seq;  // (truth, ids)
    std::vector<std::vector<double>> delays;
    std::vector<int> txs;
    sim::SimEvent ev;
    CleanCsi clean;
    while (simulator.next(ev))
    {
        if (ev.kind != sim::SimEvent::Kind::Csi) continue;
        if (pre.process(*ev.csi, clean) != RejectReason::Accepted) continue;
        const unsigned n = clean.nRx;
        std::vector<uint8_t> truth(
            ev.frame.packet.jumpState.begin(), ev.frame.packet.jumpState.begin() + n);
        seq.emplace_back(truth, clean.chainState);
        delays.push_back(clean.chainDelay_s);
        txs.push_back(int(ev.frame.transmitterIndex));
    }
    Detection d;
    d.frames = seq.size();
    if (seq.empty()) return d;
    const unsigned n = unsigned(seq.front().first.size());
    for (unsigned i = 1; i < n; ++i)
    {
        std::map<std::pair<uint8_t, uint8_t>, size_t> votes;
        std::map<uint8_t, std::pair<double, size_t>> centre;
        for (size_t f = 0; f < seq.size(); ++f)
        {
            votes[{seq[f].second[i], seq[f].first[i]}]++;
            centre[seq[f].first[i]].first += delays[f][i];
            centre[seq[f].first[i]].second++;
        }
        std::map<uint8_t, std::pair<uint8_t, size_t>> idToTruth;
        for (const auto& [k, v] : votes)
            if (v > idToTruth[k.first].second) idToTruth[k.first] = {k.second, v};
        uint8_t lastId = kUnknownChainState;
        for (size_t f = 0; f < seq.size(); ++f)
        {
            const uint8_t id = seq[f].second[i];
            if (id == kUnknownChainState) ++d.unknown;
            if (id != kUnknownChainState && idToTruth[id].first == seq[f].first[i]) ++d.agree;
            if (f > 0 && seq[f].first[i] != seq[f - 1].first[i]) ++d.trueChanges;
            if (id != kUnknownChainState)
            {
                if (lastId != kUnknownChainState && id != lastId) ++d.detectedChanges;
                lastId = id;
            }
            const auto& c = centre[seq[f].first[i]];
            d.maxDeviation_ns = std::max(
                d.maxDeviation_ns, std::abs(delays[f][i] - c.first / double(c.second)) * 1e9);
        }
    }
    d.frames *= (n - 1);
    if (std::getenv("CHAIN_STATES_DUMP"))
    {
        std::ofstream o(std::getenv("CHAIN_STATES_DUMP"), std::ios::app);
        for (size_t f = 0; f < seq.size(); ++f)
            for (unsigned i = 1; i < n; ++i)
                o << i << "," << int(seq[f].first[i]) << "," << delays[f][i] * 1e9 << "," << txs[f]
                  << "," << f << "\n";
    }
    return d;
}
}  // namespace

// The figures this classifier reaches today on random rooms at 0.2 Hz switching (development
// seeds 3 and 7): 93.8 / 93.4 % of classified chain-frames in the right state, 8.5 / 20 %
// "unknown" (no bearing from them), 35 / 24 changes detected for 30 / 20 true ones. Issue 21
// asks for more; these bounds keep it from getting worse.
TEST(ChainStates, DetectedOnSimulatedFramesWithKnownStates)
{
    for (uint32_t seed : {3u, 7u})
    {
        const Detection d = detect(jumpyRoom(seed, 0.2, 40));
        std::cout << "seed " << seed << ": " << d.frames << " chain-frames, " << d.agree
                  << " agree, " << d.unknown << " unknown, true changes " << d.trueChanges
                  << ", detected " << d.detectedChanges << ", max deviation " << d.maxDeviation_ns
                  << " ns\n";
        ASSERT_GT(d.frames, 1000u);
        EXPECT_GE(double(d.agree), 0.92 * double(d.frames - d.unknown)) << "seed " << seed;
        EXPECT_LE(double(d.unknown), 0.25 * double(d.frames)) << "seed " << seed;
        EXPECT_GT(d.trueChanges, 0u);
        EXPECT_GE(d.detectedChanges, d.trueChanges) << "seed " << seed;
        EXPECT_LE(double(d.detectedChanges), 1.3 * double(d.trueChanges)) << "seed " << seed;
    }
}

TEST(ChainStates, WeakLinksAreStillClassified)
{
    // Issue 21 at 10 dB: the neighbouring-subcarrier phase slope strays by several ns and almost
    // no frame got a state (21 bearings of 4488 in the evaluation rooms); the cross spectrum's
    // delay profile classifies most of them. Here without a calibration (states discovered from
    // scratch, the hard case): measured 78 % / 96 % of chain-frames classified, 82 % / 80 % of
    // those in the right state (development seeds 3 / 7, 0.2 Hz); with the states known from a
    // calibration the bearings hold (README: jump-state table).
    for (uint32_t seed : {3u, 7u})
    {
        auto sc = jumpyRoom(seed, 0.2, 20);
        sc.impairments.fixedSnr_dB = 10;
        const Detection d = detect(sc);
        std::cout << "seed " << seed << " at 10 dB: " << d.frames << " chain-frames, " << d.agree
                  << " agree, " << d.unknown << " unknown, true changes " << d.trueChanges
                  << ", detected " << d.detectedChanges << "\n";
        ASSERT_GT(d.frames, 1000u);
        EXPECT_LE(double(d.unknown), 0.3 * double(d.frames)) << "seed " << seed;
        EXPECT_GE(double(d.agree), 0.75 * double(d.frames - d.unknown)) << "seed " << seed;
    }
}

TEST(ChainStates, NoStateChangeWithoutJumps)
{
    for (uint32_t seed : {3u, 7u})
    {
        const Detection d = detect(jumpyRoom(seed, 0, 40));
        std::cout << "seed " << seed << ": " << d.unknown << " of " << d.frames
                  << " chain-frames unknown, " << d.detectedChanges << " changes, max deviation "
                  << d.maxDeviation_ns << " ns\n";
        // Today: 3 spurious changes in 40 s on seed 3 (multipath moving one frame's delay).
        EXPECT_LE(d.detectedChanges, 4u) << "seed " << seed;
        EXPECT_LE(double(d.unknown), 0.05 * double(d.frames)) << "seed " << seed;
    }
}

TEST(ChainStates, CalibrationFileHoldsStatesAndOldFilesStillRead)
{
    PhaseCalibration c;
    c.device = "rt-ac86u";
    c.chanspec = Chanspec::fromString("155/80");
    c.subcarriers = {-2, -1, 1};
    c.phases_rad = {{0, 0, 0}, {0.1, 0.2, 0.3}};
    const std::string v2 = c.asYamlText();
    EXPECT_NE(v2.find("version: 2"), std::string::npos) << "no states: readable by older tools";
    ChainStateCalibration st;
    st.antenna = 1;
    st.state = 2;
    st.delay_s = 3.1e-9;
    st.deltaDelay_s = 3e-9;
    st.deltaPhase_rad = -1.25;
    st.frames = 77;
    c.chainStates.push_back(st);
    const PhaseCalibration back = PhaseCalibration::fromYamlText(c.asYamlText());
    ASSERT_EQ(back.chainStates.size(), 1u);
    EXPECT_EQ(back.chainStates[0].antenna, 1u);
    EXPECT_EQ(back.chainStates[0].state, 2);
    EXPECT_NEAR(back.chainStates[0].delay_s, 3.1e-9, 1e-15);
    EXPECT_NEAR(back.chainStates[0].deltaDelay_s, 3e-9, 1e-15);
    EXPECT_NEAR(back.chainStates[0].deltaPhase_rad, -1.25, 1e-12);
    EXPECT_EQ(back.chainStates[0].frames, 77u);
    EXPECT_EQ(back.matchChainState(1, 2.5e-9), &back.chainStates[0]);
    EXPECT_EQ(back.matchChainState(1, 0.5e-9), nullptr);
    const PhaseCalibration old = PhaseCalibration::fromYamlText(v2);
    EXPECT_TRUE(old.chainStates.empty());
    // A state on the reference antenna, or a key only version 3 knows in a version 2 file.
    auto bad = c;
    bad.chainStates[0].antenna = 0;
    EXPECT_THROW(bad.validate(), CalibrationError);
    std::string v3 = c.asYamlText();
    v3.replace(v3.find("version: 3"), 10, "version: 2");
    EXPECT_THROW(PhaseCalibration::fromYamlText(v3), CalibrationError);
}

TEST(ChainStates, TrueStatesUndoTheJumpsInTheSimulator)
{
    // With every frame's true state corrected by the truth calibration's state table, the
    // chains' phases equal the same room's without jumps (the simulator's model and the file's
    // convention agree).
    sim::Scenario withJumps = jumpyRoom(5, 0.5, 10), without = jumpyRoom(5, 0, 10);
    withJumps.impairments.awgn = without.impairments.awgn =
        false;  // same noise, rotated: not equal
    sim::Simulator a(withJumps), b(without);
    const AntennaArray rx = fromSimArray(withJumps.receiver.array);
    const Chanspec cs = withJumps.transmitters.front().chanspec;
    const PhaseCalibration cal = truthCalibration(a, rx, cs);
    ASSERT_FALSE(cal.chainStates.empty());
    PreprocessOptions po;
    po.removeSamplingTimeOffset = false;
    po.normalizePower = false;
    CsiPreprocessor pa(po, rx), pb(po, rx);
    sim::SimEvent ea, eb;
    CleanCsi ca, cb;
    size_t compared = 0, jumped = 0;
    double worst = 0;
    while (a.next(ea) && b.next(eb))
    {
        if (ea.kind != sim::SimEvent::Kind::Csi) continue;
        ASSERT_EQ(eb.kind, sim::SimEvent::Kind::Csi);
        if (pa.process(*ea.csi, ca) != RejectReason::Accepted) continue;
        ASSERT_EQ(pb.process(*eb.csi, cb), RejectReason::Accepted);
        const auto& layout = *ca.layout;
        for (unsigned i = 1; i < ca.nRx; ++i)
        {
            const uint8_t s = ea.frame.packet.jumpState[i];
            jumped += s != 0;
            const ChainStateCalibration* st = cal.findChainState(i, s);
            ASSERT_NE(st, nullptr);
            std::complex<double> acc{0, 0};
            for (size_t j = 0; j < layout.size(); ++j)
            {
                const auto undo = std::polar(
                    1.0,
                    2 * M_PI * kSubcarrierSpacingHz * st->deltaDelay_s * layout.subcarriers[j] -
                        st->deltaPhase_rad);
                const std::complex<double> x =
                    std::complex<double>(ca.H(i, Eigen::Index(j))) *
                    std::conj(std::complex<double>(ca.H(0, Eigen::Index(j))));
                const std::complex<double> y =
                    std::complex<double>(cb.H(i, Eigen::Index(j))) *
                    std::conj(std::complex<double>(cb.H(0, Eigen::Index(j))));
                acc += x * undo * std::conj(y);
            }
            worst = std::max(worst, std::abs(std::arg(acc)));
        }
        ++compared;
    }
    EXPECT_GT(compared, 100u);
    EXPECT_GT(jumped, 10u);
    EXPECT_LT(worst * 180 / M_PI, 0.05);
}

namespace
{
/** A random room on channel 6 at 20 MHz whose chains jump among the delay states a real
 *  RT-AC86U shows there (−20.9, −9.0, +4.1, +16.0 ns, ~12.5 ns apart, sample slips that leave
 *  the phase at the centre frequency alone: the muTrack splitter captures). */
sim::Scenario realStatesRoom20(uint32_t seed, double rate_Hz, double duration_s)
{
    sim::Scenario sc = jumpyRoom(seed, rate_Hz, duration_s);
    for (auto& tx : sc.transmitters) tx.chanspec = Chanspec::fromString("6/20");
    sc.impairments.jumpStateDelays_s = {-20.9e-9, -9.0e-9, 4.1e-9, 16.0e-9};
    sc.impairments.jumpStates = 4;
    sc.impairments.jumpBaseband = true;
    sc.impairments.jumpStatePhase = false;
    return sc;
}
}  // namespace

TEST(ChainStates, RealSizedStatesAt20MHzAreDetectedTrackedAndCorrected)
{
    // Issue 54.4: states one 80 MHz sample apart at 20 MHz, where the per-frame delay noise is
    // also four times the 80 MHz one. Detected and tracked (the recorder, no calibration): one
    // tracker state per true state, frames in the right one, the changes counted once.
    const sim::Scenario sc = realStatesRoom20(3, 0.2, 40);
    {
        sim::Simulator simulator(sc);
        ChainStateRecorder recorder;
        std::vector<std::map<std::pair<uint8_t, uint8_t>, size_t>> votes(4);
        std::vector<std::set<uint8_t>> visited(4);
        size_t frames = 0, unknown = 0, classified = 0;
        uint64_t trueChanges = 0;
        std::vector<uint8_t> lastTruth;
        sim::SimEvent ev;
        while (simulator.next(ev))
        {
            if (ev.kind != sim::SimEvent::Kind::Csi) continue;
            auto frame = ev.csi;
            recorder.record(*frame);
            if (frame->chainState.empty()) continue;
            ++frames;
            const std::vector<uint8_t> truth(
                ev.frame.packet.jumpState.begin(), ev.frame.packet.jumpState.begin() + 4);
            for (unsigned i = 1; i < 4; ++i)
            {
                visited[i].insert(truth[i]);
                if (!lastTruth.empty() && truth[i] != lastTruth[i]) ++trueChanges;
                if (frame->chainState[i] == kUnknownChainState)
                    ++unknown;
                else
                    ++classified, votes[i][{frame->chainState[i], truth[i]}]++;
            }
            lastTruth = truth;
        }
        ASSERT_GT(frames, 500u);
        size_t agree = 0;
        for (unsigned i = 1; i < 4; ++i)
        {
            // Each tracker id stands for the true state most of its frames were in.
            std::map<uint8_t, std::pair<uint8_t, size_t>> best;
            for (const auto& [k, n] : votes[i])
                if (n > best[k.first].second) best[k.first] = {k.second, n};
            std::set<uint8_t> covered;
            for (const auto& [id, b] : best) agree += b.second, covered.insert(b.first);
            EXPECT_EQ(best.size(), visited[i].size())
                << "chain " << i << ": states found vs visited\n"
                << recorder.summary();
            EXPECT_EQ(covered, visited[i]) << "chain " << i << "\n" << recorder.summary();
        }
        std::cout << frames << " frames: " << agree << " of " << classified
                  << " classified chain-frames in the right state, " << unknown
                  << " unknown; changes " << recorder.changes() << " detected, " << trueChanges
                  << " true\n"
                  << recorder.summary();
        EXPECT_GE(double(agree), 0.97 * double(classified));
        EXPECT_LE(double(unknown), 0.2 * double(unknown + classified));
        EXPECT_GE(recorder.changes(), trueChanges);
        EXPECT_LE(double(recorder.changes()), 1.3 * double(trueChanges));
    }

    // Corrected: with the states in the calibration (as wifi-calibrate writes it at 20 MHz),
    // every chain's phase equals the same room's without jumps, and few frames are left out.
    sim::Scenario withJumps = sc, without = sc;
    without.impairments.antennaJumps = false;
    withJumps.impairments.awgn = without.impairments.awgn = false;
    sim::Simulator a(withJumps), b(without);
    const AntennaArray rx = fromSimArray(sc.receiver.array);
    PhaseCalibration cal = truthCalibration(a, rx, sc.transmitters.front().chanspec);
    cal.chainStateTolerance_s = 4e-9;
    const PhaseCalibration plain = truthCalibration(b, rx, sc.transmitters.front().chanspec);
    PreprocessOptions po;
    po.removeSamplingTimeOffset = false;
    po.normalizePower = false;
    CsiPreprocessor pa(po, rx, CalibrationStore::fromCalibration(cal)),
        pb(po, rx, CalibrationStore::fromCalibration(plain));
    sim::SimEvent ea, eb;
    CleanCsi ca, cb;
    size_t frames = 0, corrected = 0, jumped = 0, wrong = 0;
    std::vector<double> errors_deg;
    while (a.next(ea) && b.next(eb))
    {
        if (ea.kind != sim::SimEvent::Kind::Csi) continue;
        ++frames;
        if (pa.process(*ea.csi, ca) != RejectReason::Accepted) continue;
        ASSERT_EQ(pb.process(*eb.csi, cb), RejectReason::Accepted);
        ++corrected;
        for (unsigned i = 1; i < ca.nRx; ++i)
        {
            jumped += ea.frame.packet.jumpState[i] != 0;
            std::complex<double> acc{0, 0};
            for (Eigen::Index j = 0; j < ca.H.cols(); ++j)
                acc +=
                    std::complex<double>(ca.H(i, j)) * std::conj(std::complex<double>(cb.H(i, j)));
            errors_deg.push_back(std::abs(std::arg(acc)) * 180 / M_PI);
            wrong += errors_deg.back() > 5;
        }
    }
    std::sort(errors_deg.begin(), errors_deg.end());
    std::cout << pa.chainStateTrackers().front()->summary() << corrected << " of " << frames
              << " frames corrected; chain phase error median " << errors_deg[errors_deg.size() / 2]
              << " deg, p99 " << errors_deg[errors_deg.size() * 99 / 100] << " deg, " << wrong
              << " chain-frames beyond 5 deg\n";
    EXPECT_GT(jumped, 100u);
    EXPECT_GE(double(corrected), 0.8 * double(frames));
    EXPECT_LT(errors_deg[errors_deg.size() * 99 / 100], 0.5);
    EXPECT_LE(double(wrong), 0.002 * double(errors_deg.size()));  // measured: 9 of 16005
}

TEST(ChainStateRecorder, RecordsWhatTheBearingChainClassifies)
{
    // The sensor records states on the raw frames; the bearing chain classifies them again on
    // its preprocessed CSI. Same classifier, same frames: the same ids, delays and changes.
    const auto sc = jumpyRoom(3, 0.2, 20);
    sim::Simulator simulator(sc);
    CsiPreprocessor pre({}, fromSimArray(sc.receiver.array));
    ChainStateRecorder recorder;
    sim::SimEvent ev;
    CleanCsi clean;
    size_t frames = 0, sameIds = 0, truthChanges = 0;
    std::vector<uint8_t> lastTruth;
    while (simulator.next(ev))
    {
        if (ev.kind != sim::SimEvent::Kind::Csi) continue;
        auto frame = ev.csi;
        recorder.record(*frame);
        if (pre.process(*frame, clean) != RejectReason::Accepted) continue;
        ++frames;
        ASSERT_EQ(frame->chainState.size(), clean.chainState.size());
        ASSERT_EQ(frame->chainDelay_ns.size(), clean.chainDelay_s.size());
        sameIds += frame->chainState == clean.chainState;
        for (size_t i = 1; i < clean.chainDelay_s.size(); ++i)
        {
            if (clean.chainState[i] == kUnknownChainState) continue;
            EXPECT_NEAR(frame->chainDelay_ns[i], clean.chainDelay_s[i] * 1e9, 0.05);
        }
        std::vector<uint8_t> truth(
            ev.frame.packet.jumpState.begin(), ev.frame.packet.jumpState.begin() + frame->nRx);
        truthChanges += !lastTruth.empty() && truth != lastTruth;
        lastTruth = truth;
    }
    ASSERT_GT(frames, 500u);
    EXPECT_EQ(sameIds, frames);
    EXPECT_EQ(recorder.changes(), pre.chainStateChanges());
    EXPECT_GT(truthChanges, 0u);
    EXPECT_GT(recorder.changes(), 0u);
    EXPECT_GE(recorder.chainsWithJumps(), 1u);
    EXPECT_NE(recorder.summary().find("state changes"), std::string::npos) << recorder.summary();
}

TEST(ChainStates, NoStateChangeOnRealUbiLocateCaptures)
{
    // UbiLocate's closed driver suppresses the jumps: its captures must show no change, and no
    // step between consecutive frames near a jump's 3 ns. Measured: the 4×4 capture's delays
    // stay within 0.35 ns; the 1×4 capture's drift smoothly by up to 2 ns over its ten frames
    // (largest step 0.7 ns). Ten frames are fewer than a new state needs to be established, so
    // they stay "unknown": the delays are the evidence.
    for (const char* name : {"ubilocate_4x4_80mhz.pcap", "ubilocate_1x4_80mhz.pcap"})
    {
        MRPT_WIFI_REQUIRE_REAL_CAPTURE(path, name);
        ChainStateRecorder recorder;
        std::vector<CObservationWiFiCSI::Ptr> frames;
        readCsiFrames(path, {}, [&](CObservationWiFiCSI::Ptr&& f) { frames.push_back(f); });
        ASSERT_GE(frames.size(), 9u) << name;
        std::vector<float> previous;
        double largestStep_ns = 0;
        for (const auto& f : frames)
        {
            recorder.record(*f);
            ASSERT_EQ(f->chainState.size(), 4u) << name;
            for (unsigned i = 1; i < 4; ++i)
            {
                EXPECT_TRUE(f->chainState[i] == 0 || f->chainState[i] == kUnknownChainState);
                ASSERT_TRUE(std::isfinite(f->chainDelay_ns[i])) << name << " chain " << i;
                if (!previous.empty())
                    largestStep_ns = std::max(
                        largestStep_ns, double(std::abs(f->chainDelay_ns[i] - previous[i])));
            }
            previous = f->chainDelay_ns;
        }
        EXPECT_EQ(recorder.changes(), 0u) << name;
        EXPECT_EQ(recorder.chainsWithJumps(), 0u) << name;
        EXPECT_LT(largestStep_ns, 1.0) << name;
    }
}

namespace
{
/** Removes `chain`'s state farthest from its reference from `cal` (a state a short calibration
 *  drive did not visit) and returns it. */
std::optional<ChainStateCalibration> dropFarthestState(PhaseCalibration& cal, unsigned chain)
{
    auto farthest = cal.chainStates.end();
    for (auto it = cal.chainStates.begin(); it != cal.chainStates.end(); ++it)
        if (it->antenna == chain && (farthest == cal.chainStates.end() ||
                                     std::abs(it->deltaDelay_s) > std::abs(farthest->deltaDelay_s)))
            farthest = it;
    if (farthest == cal.chainStates.end()) return std::nullopt;
    const ChainStateCalibration out = *farthest;
    cal.chainStates.erase(farthest);
    return out;
}
}  // namespace

TEST(ChainStates, StateMissingFromTheCalibrationIsNamedThenLearntOnline)
{
    // The calibration drive never saw one state of chain 1: frames in it give no bearing and
    // a notice names it, until its phase is learnt from the other chains; the learnt offset
    // then matches the truth.
    const sim::Scenario sc = jumpyRoom(3, 0.2, 40);
    sim::Simulator simulator(sc);
    const AntennaArray rx = fromSimArray(sc.receiver.array);
    PhaseCalibration cal = truthCalibration(simulator, rx, sc.transmitters.front().chanspec);
    // Drop chain 1's state farthest from its reference, as a short drive might.
    const std::optional<ChainStateCalibration> dropped = dropFarthestState(cal, 1);
    ASSERT_TRUE(dropped);
    ASSERT_NE(dropped->deltaDelay_s, 0.0);
    const ChainStateCalibration missing = *dropped;

    CsiPreprocessor pre({}, rx, CalibrationStore::fromCalibration(cal));
    sim::SimEvent ev;
    CleanCsi clean;
    size_t inMissing = 0, rejectedInMissing = 0, acceptedInMissing = 0;
    std::vector<std::string> notices;
    while (simulator.next(ev))
    {
        if (ev.kind != sim::SimEvent::Kind::Csi) continue;
        const auto why = pre.process(*ev.csi, clean);
        for (auto& n : pre.takeChainStateNotices()) notices.push_back(n);
        if (ev.frame.packet.jumpState[1] != missing.state) continue;
        ++inMissing;
        rejectedInMissing += why == RejectReason::UnknownChainState;
        acceptedInMissing += why == RejectReason::Accepted;
    }
    ASSERT_GT(inMissing, 100u) << "chain 1 never visited the dropped state";
    EXPECT_GT(rejectedInMissing, 0u);
    EXPECT_GT(acceptedInMissing, inMissing / 2) << "the state was not learnt";
    ASSERT_FALSE(notices.empty());
    bool named = false;
    for (const auto& n : notices) named = named || n.find("chain 1") != std::string::npos;
    EXPECT_TRUE(named) << notices.front();

    const auto trackers = pre.chainStateTrackers();
    ASSERT_EQ(trackers.size(), 1u);
    const ChainStateInfo* learnt = nullptr;
    for (const auto& s : trackers.front()->states(1))
        if (std::abs(s.delay_s - missing.delay_s) < 1e-9) learnt = &s;
    ASSERT_NE(learnt, nullptr) << trackers.front()->summary();
    std::cout << inMissing << " frames in the missing state, " << rejectedInMissing
              << " without a bearing; learnt " << learnt->deltaDelay_s * 1e9 << " ns "
              << learnt->deltaPhase_rad * 180 / M_PI << " deg, truth " << missing.deltaDelay_s * 1e9
              << " ns " << missing.deltaPhase_rad * 180 / M_PI << " deg\n"
              << notices.front() << "\n";
    EXPECT_EQ(learnt->origin, ChainStateOrigin::LearntOnline) << trackers.front()->summary();
    EXPECT_NEAR(learnt->deltaDelay_s * 1e9, missing.deltaDelay_s * 1e9, 0.3);
    EXPECT_LT(
        std::abs(std::remainder(learnt->deltaPhase_rad - missing.deltaPhase_rad, 2 * M_PI)) * 180 /
            M_PI,
        5.0)  // measured: 1.7°
        << "learnt " << learnt->deltaPhase_rad << " rad, truth " << missing.deltaPhase_rad;
}

namespace
{
/** A state-aware calibration of one channel: every chain's reference state at delay 0. */
PhaseCalibration referenceOnlyCalibration(unsigned nRx)
{
    PhaseCalibration c;
    c.device = "rt-ac86u";
    c.chanspec = Chanspec::fromString("155/80");
    c.subcarriers = {-2, -1, 1};
    c.phases_rad.assign(nRx, {0, 0, 0});
    for (unsigned i = 1; i < nRx; ++i)
    {
        ChainStateCalibration st;
        st.antenna = i;
        st.state = 0;
        c.chainStates.push_back(st);
    }
    return c;
}

/** Frames with chain 1 at `delay_s` until the tracker has found and classified it; returns its
 *  state id. */
uint8_t enterState(ChainStateTracker& t, double delay_s)
{
    std::vector<uint8_t> ids;
    for (int f = 0; f < 100; ++f)
    {
        t.classify({0, delay_s, 0, 0}, {1, 1, 1, 1}, ids);
        if (ids[1] != kUnknownChainState && t.info(1, ids[1]).delay_s > 1.5e-9) return ids[1];
    }
    return kUnknownChainState;
}
}  // namespace

TEST(ChainStates, WronglyLearntStateIsDroppedRelearntAndDoubtedUntilConfirmed)
{
    // Issue 53.1: a state learnt from frames whose reference bearing was off (multipath) stayed
    // wrong for minutes with a narrow σ. Its later frames disagree with it: it is dropped and
    // learnt again, and while unconfirmed its phase carries a doubt that covers the error.
    const PhaseCalibration cal = referenceOnlyCalibration(4);
    const double truth = -20 * M_PI / 180, wrong = 60 * M_PI / 180;
    for (const bool verify : {true, false})
    {
        ChainStateOptions o;
        o.verify = verify;
        ChainStateTracker t(4, &cal, o);
        const uint8_t id = enterState(t, 3e-9);
        ASSERT_NE(id, kUnknownChainState) << t.summary();
        ASSERT_EQ(t.info(1, id).origin, ChainStateOrigin::Unresolved);
        // Learnt from biased evidence: 60° where the truth is −20°.
        for (size_t f = 0; f < o.learnFrames; ++f)
            t.addLearningEvidence(1, id, std::polar(1.0, wrong));
        ASSERT_EQ(t.info(1, id).origin, ChainStateOrigin::LearntOnline);
        EXPECT_NEAR(t.info(1, id).deltaPhase_rad, wrong, 1e-9);
        EXPECT_FALSE(t.info(1, id).confirmed);
        // The error is covered meanwhile.
        EXPECT_GE(t.info(1, id).phaseDoubt_rad, M_PI / 2);

        // Later frames: the residual the other chains measure against the current correction.
        size_t framesToDrop = 0, framesToConfirm = 0;
        double worstUncovered = 0;
        for (size_t f = 0; f < 2000; ++f)
        {
            const ChainStateInfo& s = t.info(1, id);
            if (s.relearnt > 0 && !framesToDrop) framesToDrop = f;
            const double error = std::abs(std::remainder(s.deltaPhase_rad - truth, 2 * M_PI));
            if (!s.confirmed) worstUncovered = std::max(worstUncovered, error - s.phaseDoubt_rad);
            if (s.confirmed && !framesToConfirm) framesToConfirm = f;
            t.addVerificationEvidence(1, id, std::polar(1.0, truth - s.deltaPhase_rad));
        }
        const ChainStateInfo& s = t.info(1, id);
        std::cout << (verify ? "verified" : "unverified") << ": dropped after " << framesToDrop
                  << " frames, confirmed after " << framesToConfirm << ", phase "
                  << s.deltaPhase_rad * 180 / M_PI << " deg (truth " << truth * 180 / M_PI
                  << "), relearnt " << s.relearnt << "x\n"
                  << t.summary();
        if (!verify)
        {
            // Before issue 53: the wrong phase stays, trusted.
            EXPECT_NEAR(s.deltaPhase_rad, wrong, 1e-9);
            continue;
        }
        EXPECT_EQ(s.relearnt, 1u);
        EXPECT_EQ(framesToDrop, 2 * o.verifyFrames);
        EXPECT_EQ(s.origin, ChainStateOrigin::LearntOnline);
        EXPECT_TRUE(s.confirmed);
        EXPECT_EQ(s.phaseDoubt_rad, 0.0);
        EXPECT_LT(std::abs(std::remainder(s.deltaPhase_rad - truth, 2 * M_PI)), 1e-6);
        EXPECT_LE(worstUncovered, 0.0) << "an unconfirmed phase off by more than its doubt";
        const auto saved = t.learntStates();
        ASSERT_EQ(saved.size(), 1u);
        EXPECT_EQ(saved[0].antenna, 1u);
        EXPECT_NEAR(saved[0].deltaPhase_rad, truth, 1e-6);
    }
}

TEST(ChainStates, UnconfirmedStateWidensTheBearingSigma)
{
    // A learnt state's frames carry a bearing doubt (how far the array's peak moves if the
    // chain's phase is off by the state's doubt) until later frames confirm it; then none.
    const sim::Scenario sc = jumpyRoom(3, 0.2, 40);
    sim::Simulator simulator(sc);
    const AntennaArray rx = fromSimArray(sc.receiver.array);
    PhaseCalibration cal = truthCalibration(simulator, rx, sc.transmitters.front().chanspec);
    const std::optional<ChainStateCalibration> dropped = dropFarthestState(cal, 1);
    ASSERT_TRUE(dropped);
    const uint8_t missing = dropped->state;

    CsiPreprocessor pre({}, rx, CalibrationStore::fromCalibration(cal));
    sim::SimEvent ev;
    CleanCsi clean;
    size_t doubted = 0, confirmedFrames = 0, doubtAfterConfirmation = 0, otherDoubted = 0;
    double smallestDoubt = M_PI;
    while (simulator.next(ev))
    {
        if (ev.kind != sim::SimEvent::Kind::Csi) continue;
        if (pre.process(*ev.csi, clean) != RejectReason::Accepted) continue;
        const auto* t = pre.chainStateTrackers().front();
        const ChainStateInfo& s = t->info(1, clean.chainState[1]);
        if (s.origin != ChainStateOrigin::LearntOnline)
        {
            otherDoubted += clean.stateDoubt_rad > 0;
            continue;
        }
        if (ev.frame.packet.jumpState[1] != missing) continue;
        if (!s.confirmed)
        {
            ++doubted;
            smallestDoubt = std::min(smallestDoubt, clean.stateDoubt_rad);
        }
        else
        {
            ++confirmedFrames;
            doubtAfterConfirmation += clean.stateDoubt_rad > 0;
        }
    }
    std::cout << doubted << " frames doubted (smallest " << smallestDoubt * 180 / M_PI << " deg), "
              << confirmedFrames << " after confirmation\n"
              << pre.chainStateTrackers().front()->summary();
    ASSERT_GT(doubted, 50u);
    EXPECT_GT(smallestDoubt, 0.0);
    EXPECT_GT(confirmedFrames, 100u) << "never confirmed";
    EXPECT_EQ(doubtAfterConfirmation, 0u);
    EXPECT_EQ(otherDoubted, 0u) << "frames with calibrated states only got a doubt";

    // Write-back: the learnt state in the calibration, the next run learns nothing and
    // corrects the state's frames as the first run ended.
    const auto learnt = pre.calibrationsWithLearntStates();
    ASSERT_EQ(learnt.size(), 1u);
    const PhaseCalibration written = PhaseCalibration::fromYamlText(learnt[0].asYamlText());
    EXPECT_EQ(written.chainStates.size(), cal.chainStates.size() + 1);
    const ChainStateInfo* first = nullptr;
    for (const auto& s : pre.chainStateTrackers().front()->states(1))
        if (s.origin == ChainStateOrigin::LearntOnline) first = &s;
    ASSERT_NE(first, nullptr);

    sim::Simulator again(sc);
    CsiPreprocessor second({}, rx, CalibrationStore::fromCalibration(written));
    std::vector<std::string> notices;
    size_t inState = 0, accepted = 0;
    while (again.next(ev))
    {
        if (ev.kind != sim::SimEvent::Kind::Csi) continue;
        const auto why = second.process(*ev.csi, clean);
        for (auto& n : second.takeChainStateNotices()) notices.push_back(n);
        if (ev.frame.packet.jumpState[1] != missing) continue;
        ++inState;
        accepted += why == RejectReason::Accepted;
        if (why == RejectReason::Accepted)
        {
            EXPECT_EQ(clean.stateDoubt_rad, 0.0);
        }
    }
    EXPECT_TRUE(notices.empty()) << notices.front();
    const auto* t2 = second.chainStateTrackers().front();
    for (unsigned i = 1; i < t2->chains(); ++i)
        for (const auto& s : t2->states(i))
            EXPECT_EQ(s.origin, ChainStateOrigin::Calibration) << t2->summary();
    // The same correction as the first run's final one (hence the same bearings).
    bool found = false;
    for (const auto& s : t2->states(1))
        if (s.id == first->id)
        {
            found = true;
            EXPECT_NEAR(s.deltaPhase_rad, first->deltaPhase_rad, 1e-9);
            EXPECT_NEAR(s.deltaDelay_s, first->deltaDelay_s, 1e-15);
        }
    EXPECT_TRUE(found) << t2->summary();
    EXPECT_GT(accepted, inState * 8 / 10) << "frames in the written state still rejected";
}
