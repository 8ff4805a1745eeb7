/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * The simulated stream: reproducibility, time order and metadata, channel filtering, truth
 * consistent with the CSI (impairments, SNR, jumps), motion and odometry. */
#include <gtest/gtest.h>
#include <mrpt/math/wrap2pi.h>
#include <mrpt_wifi/obs/Subcarriers.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <set>
#include <tuple>

using namespace mrpt_wifi;
using namespace mrpt_wifi::sim;
using mrpt::math::wrapToPi;

namespace
{
const std::string kShare = std::string(MRPT_WIFI_SOURCE_DIR) + "/share";

Scenario baseScenario()
{
    return Scenario::fromYamlText(
        R"(name: unit
duration_s: 3
seed: 42
room:
  corners: [[0, 0], [10, 0], [10, 6], [0, 6]]
  reflection: -0.4
scatterers:
  - {position: [6, 2], rcs_m2: 0.5}
transmitters:
  - {name: a, mac: '02:00:00:00:00:01', position: [1, 1], yaw_deg: 30, channel: 155/80,
     streams: 2, array: ../arrays/ap-linear-2.yaml, frame_rate_hz: 50}
  - {name: b, mac: '02:00:00:00:00:02', position: [9, 5], yaw_deg: 200, channel: 36/20,
     frame_rate_hz: 30, first_sequence_number: 4090}
receiver:
  array: ../arrays/rt-ac86u.yaml
  sensor_pose: {x: 0.2, y: -0.1, z: 0.5, yaw_deg: 15}
motion:
  type: random_walk
  start: [5, 3, 0]
  radius_m: 2.5
odometry:
  rate_hz: 25
)",
        "unit.yaml", kShare + "/scenarios");
}

std::vector<SimEvent> runAll(Simulator& sim)
{
    std::vector<SimEvent> out;
    SimEvent ev;
    while (sim.next(ev))
    {
        out.push_back(ev);
        ev = SimEvent();  // fresh objects: keep the stored ones
    }
    return out;
}

bool sameCsi(const CObservationWiFiCSI& a, const CObservationWiFiCSI& b)
{
    return a.csi.size() == b.csi.size() &&
           std::memcmp(a.csi.data(), b.csi.data(), a.csi.size() * sizeof(a.csi[0])) == 0;
}

/** Least-squares complex scale c minimising |y − c·x|². */
std::complex<double> fitScale(
    const std::complex<float>* y, const std::complex<float>* x, const std::vector<unsigned>& bins)
{
    std::complex<double> num = 0;
    double den = 0;
    for (unsigned b : bins)
    {
        num += std::complex<double>(y[b]) * std::conj(std::complex<double>(x[b]));
        den += std::norm(std::complex<double>(x[b]));
    }
    return num / den;
}
}  // namespace

TEST(Simulator, SameSeedSameStreamDifferentSeedDifferentCsi)
{
    Simulator a(baseScenario()), b(baseScenario());
    Scenario other = baseScenario();
    other.seed = 43;
    Simulator c(other);
    const auto ea = runAll(a), eb = runAll(b), ec = runAll(c);
    ASSERT_EQ(ea.size(), eb.size());
    ASSERT_GT(ea.size(), 200u);
    size_t csiFrames = 0, differentFromOtherSeed = 0;
    for (size_t i = 0; i < ea.size(); ++i)
    {
        ASSERT_EQ(ea[i].kind, eb[i].kind);
        ASSERT_EQ(ea[i].time_s, eb[i].time_s);
        if (ea[i].kind == SimEvent::Kind::Csi)
        {
            ++csiFrames;
            EXPECT_TRUE(sameCsi(*ea[i].csi, *eb[i].csi)) << i;
            EXPECT_EQ(ea[i].frame.rssi_dBm, eb[i].frame.rssi_dBm);
        }
        else
            EXPECT_EQ(ea[i].odometry->odometry.asTPose(), eb[i].odometry->odometry.asTPose());
    }
    for (size_t i = 0; i < std::min(ea.size(), ec.size()); ++i)
        if (ea[i].kind == SimEvent::Kind::Csi && ec[i].kind == SimEvent::Kind::Csi)
            differentFromOtherSeed += !sameCsi(*ea[i].csi, *ec[i].csi);
    EXPECT_GT(csiFrames, 200u);
    EXPECT_GT(differentFromOtherSeed, csiFrames * 9 / 10);
}

TEST(Simulator, StreamIsTimeOrderedWithRealisticMetadata)
{
    Simulator sim(baseScenario());
    const Scenario& sc = sim.scenario();
    const auto events = runAll(sim);
    double last = -1;
    std::vector<int> lastSeq(2, -1);
    std::vector<unsigned> frames(2, 0);
    unsigned odometry = 0;
    for (const auto& ev : events)
    {
        EXPECT_GE(ev.time_s, last);
        last = ev.time_s;
        if (ev.kind == SimEvent::Kind::Odometry)
        {
            ++odometry;
            EXPECT_EQ(ev.odometry->sensorLabel, "ODOMETRY");
            EXPECT_NEAR(
                mrpt::Clock::toDouble(ev.odometry->timestamp), sc.startTime_unix + ev.time_s, 1e-6);
            continue;
        }
        const auto& o = *ev.csi;
        const size_t t = ev.frame.transmitterIndex;
        ++frames[t];
        EXPECT_EQ(o.sensorLabel, "WIFI_CSI");
        EXPECT_NEAR(mrpt::Clock::toDouble(o.timestamp), sc.startTime_unix + ev.time_s, 1e-6);
        EXPECT_EQ(o.transmitter, sc.transmitters[t].mac);
        EXPECT_EQ(o.chanspec, sc.transmitters[t].chanspec);
        EXPECT_EQ(o.chipId, 0x006a);
        EXPECT_EQ(o.nRx, 4);
        EXPECT_EQ(o.nTx, sc.transmitters[t].streams);
        EXPECT_TRUE(o.isComplete());
        EXPECT_EQ(o.sensorPose, sc.receiver.sensorPose);
        EXPECT_EQ(o.rssi_dBm, ev.frame.rssi_dBm);
        EXPECT_LT(o.rssi_dBm, 0);
        if (lastSeq[t] >= 0)
        {
            EXPECT_EQ(o.sequenceNumber, (lastSeq[t] + 1) % 4096);
        }
        lastSeq[t] = o.sequenceNumber;
    }
    EXPECT_NEAR(frames[0], 3 * 50, 1);
    EXPECT_NEAR(frames[1], 3 * 30, 1);
    EXPECT_EQ(odometry, 3u * 25u + 1u);
    EXPECT_EQ(lastSeq[1], (4090 + int(frames[1]) - 1) % 4096);  // wrapped past 4095
}

// Frames are pure functions of (seed, transmitter, index): the stream, random access, a
// channel filter and a rewind all give the same bytes.
TEST(Simulator, FramesAreReproducibleInAnyOrder)
{
    Simulator sim(baseScenario());
    const auto events = runAll(sim);
    Simulator other(baseScenario());
    other.setChannelFilter(Chanspec::make(36, 20));
    other.rewind(1.0);
    const auto filtered = runAll(other);
    size_t checked = 0;
    for (const auto& ev : filtered)
    {
        if (ev.kind != SimEvent::Kind::Csi) continue;
        ASSERT_EQ(ev.frame.transmitterIndex, 1u);  // only the 36/20 transmitter
        ASSERT_GE(ev.time_s, 1.0);
        for (const auto& ref : events)
            if (ref.kind == SimEvent::Kind::Csi && ref.frame.transmitterIndex == 1 &&
                ref.frame.frameIndex == ev.frame.frameIndex)
            {
                EXPECT_TRUE(sameCsi(*ref.csi, *ev.csi));
                EXPECT_EQ(ref.time_s, ev.time_s);
                ++checked;
            }
    }
    EXPECT_GT(checked, 50u);
    // Random access to a frame of the other transmitter.
    CObservationWiFiCSI obs;
    FrameTruth truth;
    for (const auto& ref : events)
        if (ref.kind == SimEvent::Kind::Csi && ref.frame.transmitterIndex == 0 &&
            ref.frame.frameIndex == 42)
        {
            other.synthesizeFrame(0, 42, obs, truth);
            EXPECT_TRUE(sameCsi(obs, *ref.csi));
            EXPECT_EQ(truth.time_s, ref.time_s);
            ++checked;
        }
    EXPECT_GT(checked, 51u);
}

// Switching the filter mid-stream: the other transmitter falls silent, the new one starts at the
// present (no frames from the past).
TEST(Simulator, ChannelSwitchSilencesTheOldChannel)
{
    Scenario sc = baseScenario();
    sc.odometry.enabled = false;
    Simulator sim(sc);
    sim.setChannelFilter(Chanspec::make(155, 80));
    SimEvent ev;
    double t = 0;
    while (sim.next(ev) && ev.time_s < 1.5)
    {
        EXPECT_EQ(ev.frame.transmitterIndex, 0u);
        t = ev.time_s;
    }
    sim.setChannelFilter(Chanspec::make(36, 20));
    unsigned afterSwitch = 0;
    while (sim.next(ev))
    {
        EXPECT_EQ(ev.frame.transmitterIndex, 1u);
        EXPECT_GE(ev.time_s, t);
        ++afterSwitch;
    }
    EXPECT_NEAR(afterSwitch, (3.0 - 1.5) * 30, 2);
    sim.rewind(0);
    sim.setChannelFilter(Chanspec::make(100, 20));  // nobody there
    EXPECT_FALSE(sim.next(ev));
}

// The truth matches the CSI: with ideal hardware the CSI is the propagation channel scaled by
// the AGC; with phase offsets on, the ratio per chain is the offsets + ripple that
// impairments.json reports; STO and CFO from frames.csv explain the rest.
TEST(Simulator, ImpairmentTruthExplainsTheCsi)
{
    Scenario sc = baseScenario();
    sc.impairments = ImpairmentSpec::ideal();
    sc.impairments.antennaPhaseOffsets = true;
    sc.impairments.rippleAmplitude_rad = 0.1;
    sc.impairments.antennaGainSigma_dB = 1.0;
    sc.impairments.samplingTimeOffsetSigma_s = 30e-9;
    sc.impairments.cfoCommonPhase = true;
    Simulator sim(sc);
    Scenario idealSc = baseScenario();
    idealSc.impairments = ImpairmentSpec::ideal();
    Simulator ideal(idealSc);

    CObservationWiFiCSI obs, ref;
    FrameTruth truth, refTruth;
    for (uint64_t n : {3u, 77u})
    {
        sim.synthesizeFrame(0, n, obs, truth);
        ideal.synthesizeFrame(0, n, ref, refTruth);
        EXPECT_EQ(truth.aoa_rad, refTruth.aoa_rad);
        const unsigned nfft = 256;
        const auto& ks = dataSubcarriers(80);
        // Common scale between the two (AGC differs), then per chain per subcarrier phase.
        std::vector<unsigned> bins;
        for (int k : ks) bins.push_back(subcarrierToBin(k, nfft));
        double worst = 0;
        for (unsigned m = 0; m < 2; ++m)
            for (unsigned i = 0; i < 4; ++i)
            {
                const auto& ch = sim.hardware().chain(obs.chanspec, i);
                for (int k : ks)
                {
                    const unsigned b = subcarrierToBin(k, nfft);
                    const double measured = std::arg(
                        std::complex<double>(obs.at(m, i, b)) /
                        std::complex<double>(ref.at(m, i, b)));
                    const double expected =
                        ch.phase_rad(k, nfft) -
                        2 * M_PI * k * kSubcarrierSpacingHz * truth.packet.samplingTimeOffset_s +
                        truth.packet.cfoPhase_rad;
                    worst = std::max(worst, std::abs(wrapToPi(measured - expected)));
                }
            }
        EXPECT_LT(worst, 1e-4) << "frame " << n;
        // The reported CSI has the AGC's target level.
        double power = 0;
        for (unsigned q = 0; q < 8; ++q)
            for (int k : ks) power += std::norm(obs.csi[q * nfft + subcarrierToBin(k, nfft)]);
        EXPECT_NEAR(std::sqrt(power / (8 * ks.size())), 1.0, 0.3);
    }
}

TEST(Simulator, HardwareQuirks)
{
    Scenario sc = baseScenario();
    sc.impairments = ImpairmentSpec::ideal();
    Simulator clean(sc);
    sc.impairments.lowerSubbandSignFlip = true;
    sc.impairments.firmwareOverwrittenBins = true;
    sc.impairments.deadCores = {2};
    Simulator quirky(sc);
    CObservationWiFiCSI a, b;
    FrameTruth ta, tb;
    clean.synthesizeFrame(0, 5, a, ta);
    quirky.synthesizeFrame(0, 5, b, tb);
    for (unsigned bin = 6; bin < 251; ++bin)
    {
        const int k = binToSubcarrier(bin, 256);
        if (k >= 0 && k <= 2) continue;
        const auto expected = bin < 64 ? -a.at(0, 0, bin) : a.at(0, 0, bin);
        EXPECT_LT(std::abs(b.at(0, 0, bin) - expected), 1e-5f * (1 + std::abs(expected))) << k;
        EXPECT_EQ(b.at(0, 2, bin), std::complex<float>(0, 0));  // dead core: zeros
    }
    EXPECT_TRUE(b.isPresent(0, 2));
    int garbage = 0;
    for (int k : firmwareOverwrittenSubcarriers(80))
        garbage +=
            std::abs(b.at(1, 3, subcarrierToBin(k, 256)) - a.at(1, 3, subcarrierToBin(k, 256))) >
            1e-3f;
    EXPECT_EQ(garbage, 3);

    sc.impairments.deadCoresMissing = true;
    Simulator missing(sc);
    missing.synthesizeFrame(0, 5, b, tb);
    EXPECT_FALSE(b.isPresent(0, 2));
    EXPECT_FALSE(b.isComplete());
}

// AWGN at a fixed SNR: the residual against the scaled ideal channel has the right power, zero
// mean, and is circular.
TEST(Simulator, NoiseHasTheRequestedSnrAndIsCircular)
{
    Scenario sc = baseScenario();
    sc.impairments = ImpairmentSpec::ideal();
    Simulator ideal(sc);
    sc.impairments.awgn = true;
    sc.impairments.fixedSnr_dB = 10.0;
    Simulator noisy(sc);
    const unsigned nfft = 256;
    std::vector<unsigned> bins;
    for (int k : dataSubcarriers(80)) bins.push_back(subcarrierToBin(k, nfft));
    double ratioSum = 0;
    std::complex<double> mean = 0, pseudo = 0;
    double var = 0;
    size_t count = 0;
    const int frames = 40;
    for (int n = 0; n < frames; ++n)
    {
        CObservationWiFiCSI a, b;
        FrameTruth ta, tb;
        ideal.synthesizeFrame(0, uint64_t(n), a, ta);
        noisy.synthesizeFrame(0, uint64_t(n), b, tb);
        EXPECT_DOUBLE_EQ(tb.snr_dB, 10.0);
        double signal = 0, noise = 0;
        for (unsigned q = 0; q < 8; ++q)
        {
            const auto* x = a.csi.data() + q * nfft;
            const auto* y = b.csi.data() + q * nfft;
            const auto c = fitScale(y, x, bins);
            for (unsigned bin : bins)
            {
                const std::complex<double> s = c * std::complex<double>(x[bin]);
                const std::complex<double> r = std::complex<double>(y[bin]) - s;
                signal += std::norm(s);
                noise += std::norm(r);
                mean += r;
                pseudo += r * r;
                var += std::norm(r);
                ++count;
            }
        }
        ratioSum += signal / noise;
    }
    EXPECT_NEAR(10 * std::log10(ratioSum / frames), 10.0, 0.5);
    EXPECT_LT(std::abs(mean) / count, 0.05 * std::sqrt(var / count));
    EXPECT_LT(std::abs(pseudo) / var, 0.05);  // E[n²] ≈ 0: circular
}

/** Frames of a static simulation whose chain 1 is in another jump state than in frame 0 (chain
 *  0 unchanged): chain 1's phase relative to chain 0 at a few subcarriers k has moved by
 *  expected(k, state in frame 0, state later), nothing else. */
void expectRelativePhaseFollowsTheStates(
    Simulator& sim, const std::function<double(int, uint8_t, uint8_t)>& expected)
{
    CObservationWiFiCSI first, later;
    FrameTruth t0, t1;
    sim.synthesizeFrame(0, 0, first, t0);
    int compared = 0;
    for (uint64_t n = 1; n < 400 && compared < 3; n += 7)
    {
        sim.synthesizeFrame(0, n, later, t1);
        const uint8_t s0 = t0.packet.jumpState[1], s1 = t1.packet.jumpState[1];
        if (s0 == s1 || t1.packet.jumpState[0] != t0.packet.jumpState[0]) continue;
        ++compared;
        for (int k : {-100, -3, 50, 120})
        {
            const unsigned b = subcarrierToBin(k, 256);
            const auto rel0 =
                std::complex<double>(first.at(0, 1, b)) / std::complex<double>(first.at(0, 0, b));
            const auto rel1 =
                std::complex<double>(later.at(0, 1, b)) / std::complex<double>(later.at(0, 0, b));
            EXPECT_NEAR(wrapToPi(std::arg(rel1 / rel0) - expected(k, s0, s1)), 0.0, 1e-3)
                << "k=" << k;
        }
    }
    EXPECT_GE(compared, 1);
}

// Jump states: chain 1's phase relative to chain 0 moves by −2π·f_k·Δstate·step between frames
// in different states, nothing else changing (static robot).
TEST(Simulator, AntennaJumpStatesShiftTheRelativePhase)
{
    Scenario sc = baseScenario();
    sc.motion.type = MotionType::Static;
    sc.impairments = ImpairmentSpec::ideal();
    sc.impairments.antennaJumps = true;
    sc.impairments.jumpStates = 3;
    sc.impairments.jumpStep_s = 3e-9;
    sc.impairments.jumpRate_Hz = 5;
    sc.duration_s = 10;
    Simulator sim(sc);
    ASSERT_GT(sim.hardware().jumpEvents(1).size(), 5u);
    expectRelativePhaseFollowsTheStates(
        sim,
        [&](int k, uint8_t s0, uint8_t s1) {
            return -2 * M_PI * subcarrierFrequencyHz(Chanspec::make(155, 80), k) * (s1 - s0) * 3e-9;
        });
}

// Issue 54: listed state delays, as sample slips (baseband): chain 1's phase relative to chain
// 0 moves by −2π·k·Δf·(τ_s − τ_s') only, the phase at the centre frequency unchanged.
TEST(Simulator, ListedJumpStatesAsSampleSlips)
{
    Scenario sc = baseScenario();
    sc.motion.type = MotionType::Static;
    sc.impairments = ImpairmentSpec::ideal();
    sc.impairments.antennaJumps = true;
    sc.impairments.jumpStateDelays_s = {-20.9e-9, -9.0e-9, 4.1e-9, 16.0e-9};
    sc.impairments.jumpStates = 4;
    sc.impairments.jumpBaseband = true;
    sc.impairments.jumpRate_Hz = 5;
    sc.duration_s = 10;
    Simulator sim(sc);
    EXPECT_DOUBLE_EQ(sim.hardware().jumpStateDelay_s(2), 4.1e-9);
    EXPECT_EQ(sim.hardware().jumpDelay_s(0, 1.0), 0.0) << "chain 0 is the reference";
    const auto& delays = sc.impairments.jumpStateDelays_s;
    expectRelativePhaseFollowsTheStates(
        sim, [&](int k, uint8_t s0, uint8_t s1)
        { return -2 * M_PI * k * kSubcarrierSpacingHz * (delays[s1] - delays[s0]); });
}

TEST(Simulator, RebootDrawsNewPhaseOffsets)
{
    Simulator sim(baseScenario());
    const Chanspec cs = Chanspec::make(155, 80);
    const double before = sim.hardware().chain(cs, 1).phaseOffset_rad;
    EXPECT_EQ(sim.hardware().chain(cs, 1).phaseOffset_rad, before);  // stable within a boot
    sim.reboot();
    EXPECT_EQ(sim.hardware().boot(), 1u);
    EXPECT_NE(sim.hardware().chain(cs, 1).phaseOffset_rad, before);
}

TEST(Simulator, ChainOffsetsFollowTheirDelaysAcrossChannels)
{
    // offset_i(c) = offset_i(ref) − 2π·(f_c − f_ref)·τ_i: the reference is the first
    // transmitter's channel (155/80), τ_i drawn (σ 1 ns) or listed.
    Scenario sc = baseScenario();
    ASSERT_TRUE(sc.impairments.chainPhaseReference);
    EXPECT_EQ(sc.impairments.chainPhaseReference->asString(), "155/80");
    const Chanspec ref = Chanspec::make(155, 80);
    for (const bool listed : {false, true})
    {
        if (listed) sc.impairments.chainDelays_s = {0.0, 0.5e-9, -1.2e-9, 2.0e-9};
        Simulator sim(sc);
        const auto& hw = sim.hardware();
        for (unsigned rx = 1; rx < 4; ++rx)
        {
            const double tau = hw.chainDelay_s(rx);
            if (listed)
            {
                EXPECT_EQ(tau, sc.impairments.chainDelays_s[rx]);
            }
            EXPECT_GT(std::abs(tau), 1e-12) << "chain " << rx;
            for (const char* other : {"42/80", "106/80", "6/20", "36/20"})
            {
                const Chanspec cs = Chanspec::fromString(other);
                const double expected =
                    hw.chain(ref, rx).phaseOffset_rad -
                    2 * M_PI * (cs.centerFrequencyHz() - ref.centerFrequencyHz()) * tau;
                EXPECT_NEAR(wrapToPi(hw.chain(cs, rx).phaseOffset_rad - expected), 0.0, 1e-9)
                    << other << " chain " << rx;
            }
        }
    }
    // Without delays every channel has the reference's offsets; gains and ripple stay per
    // channel.
    sc.impairments.chainDelays_s = {0.0, 0.0, 0.0, 0.0};
    Simulator flat(sc);
    const Chanspec low = Chanspec::make(42, 80);
    for (unsigned rx = 0; rx < 4; ++rx)
    {
        EXPECT_NEAR(
            wrapToPi(
                flat.hardware().chain(low, rx).phaseOffset_rad -
                flat.hardware().chain(ref, rx).phaseOffset_rad),
            0.0, 1e-12);
        EXPECT_NE(flat.hardware().chain(low, rx).gain_dB, flat.hardware().chain(ref, rx).gain_dB);
    }
}

TEST(Simulator, TruthGeometry)
{
    Simulator sim(baseScenario());
    CObservationWiFiCSI obs;
    FrameTruth f;
    sim.synthesizeFrame(0, 20, obs, f);
    const auto& tx = sim.scenario().transmitters[0];
    const double dx = tx.pose.x - f.sensorPose.x, dy = tx.pose.y - f.sensorPose.y;
    EXPECT_NEAR(f.losDistance_m, std::hypot(dx, dy), 1e-9);
    EXPECT_NEAR(f.losDelay_s, std::hypot(dx, dy) / kSpeedOfLight, 1e-15);
    EXPECT_NEAR(f.aoa_rad, wrapToPi(std::atan2(dy, dx) - f.sensorPose.phi), 1e-9);
    EXPECT_NEAR(f.aod_rad, wrapToPi(std::atan2(-dy, -dx) - tx.pose.phi), 1e-9);
    // Sensor pose = robot pose ⊕ mounting (0.2, −0.1, 15°).
    const auto& r = f.robotPose;
    EXPECT_NEAR(f.sensorPose.x, r.x + 0.2 * std::cos(r.phi) + 0.1 * std::sin(r.phi), 1e-9);
    EXPECT_NEAR(f.sensorPose.y, r.y + 0.2 * std::sin(r.phi) - 0.1 * std::cos(r.phi), 1e-9);
    EXPECT_NEAR(wrapToPi(f.sensorPose.phi - r.phi), 15 * M_PI / 180, 1e-9);
    EXPECT_EQ(f.pathCount, sim.pathsAt(0, f.robotPose).size());
    EXPECT_GT(f.pathCount, 5u);  // room reflections and the scatterer
}

TEST(Simulator, MotionStaysInsideLimits)
{
    Scenario sc = baseScenario();
    sc.duration_s = 120;
    Simulator sim(sc);
    const auto& tr = sim.trajectory();
    EXPECT_GT(tr.pathLength_m(), 0.3 * sc.motion.speed_mps * sc.duration_s);
    EXPECT_GT(tr.goalsReached(), 5u);
    const auto& s = tr.samples();
    for (size_t i = 1; i < s.size(); ++i)
    {
        ASSERT_TRUE(sc.insideRoom({s[i].x, s[i].y}));
        const double step = std::hypot(s[i].x - s[i - 1].x, s[i].y - s[i - 1].y);
        EXPECT_LE(step, sc.motion.speed_mps * tr.timeStep() + 1e-9);
        EXPECT_LE(
            std::abs(wrapToPi(s[i].phi - s[i - 1].phi)),
            sc.motion.turnRate_radps * tr.timeStep() + 1e-9);
        EXPECT_LE(std::hypot(s[i].x - 5, s[i].y - 3), sc.motion.randomWalkRadius_m + 0.5);
    }
}

TEST(Simulator, OdometryNoiseAndDrift)
{
    Scenario sc = baseScenario();
    sc.duration_s = 60;
    sc.motion.type = MotionType::Loop;
    sc.motion.waypoints = {{8, 1}, {8, 5}, {2, 5}, {2, 1}};
    sc.odometry.sigmaXY_m_per_sqrt_m = 0;
    sc.odometry.sigmaYaw_rad_per_sqrt_m = 0;
    sc.odometry.sigmaYaw_rad_per_sqrt_rad = 0;
    {
        Simulator exact(sc);
        const auto& odo = exact.odometry();
        const auto origin = odo.front().truth;
        for (const auto& s : odo)
        {
            // Noise-free odometry: the truth seen from the start pose.
            const auto rel = s.truth - origin;
            EXPECT_NEAR(s.odometry.x, rel.x, 1e-6);
            EXPECT_NEAR(s.odometry.y, rel.y, 1e-6);
            EXPECT_NEAR(wrapToPi(s.odometry.phi - rel.phi), 0, 1e-6);
        }
    }
    sc.odometry.yawDrift_rad_per_m = 1.0 * M_PI / 180;
    Simulator drifting(sc);
    const auto& odo = drifting.odometry();
    const auto rel = odo.back().truth - odo.front().truth;
    const double yawError = std::abs(wrapToPi(odo.back().odometry.phi - rel.phi));
    const double driven = drifting.trajectory().pathLength_m();
    // All of the heading error is the drift: 1°/m over the distance driven.
    EXPECT_GT(driven, 15.0);
    EXPECT_NEAR(wrapToPi(odo.back().odometry.phi - rel.phi - driven * M_PI / 180), 0.0, 0.02);
    EXPECT_GT(yawError, 0.1);
}

// Issue 54: real RT-AC86Us hear about 4.5 % of frames twice, as 802.11 retries: the same
// sequence number 0.02–7 ms later, another reception (its own noise). The stream has them when
// asked, in time order.
TEST(Simulator, RetriesAreFurtherReceptionsOfTheSameFrame)
{
    Scenario sc = baseScenario();
    sc.impairments.retryProbability = 0.3;
    sc.odometry.rate_Hz = 1;
    Simulator sim(sc);
    SimEvent ev;
    std::map<std::pair<size_t, uint64_t>, std::pair<double, CObservationWiFiCSI::Ptr>> first;
    size_t frames = 0, retries = 0;
    double lastTime = -1;
    for (size_t guard = 0; guard < 100000 && sim.next(ev); ++guard)
    {
        EXPECT_GE(ev.time_s, lastTime);
        lastTime = ev.time_s;
        if (ev.kind != SimEvent::Kind::Csi) continue;
        const auto key = std::make_pair(ev.frame.transmitterIndex, ev.frame.frameIndex);
        if (ev.frame.reception == 0)
        {
            ++frames;
            first[key] = {ev.time_s, CObservationWiFiCSI::Create(*ev.csi)};
            continue;
        }
        ++retries;
        ASSERT_TRUE(first.count(key));
        const auto& [t0, original] = first.at(key);
        EXPECT_EQ(ev.csi->sequenceNumber, original->sequenceNumber);
        EXPECT_GE(ev.time_s - t0, 20e-6);
        EXPECT_LE(ev.time_s - t0, 7e-3);
        EXPECT_NE(ev.csi->csi, original->csi);  // its own noise and offsets
        // The same channel: the magnitudes across subcarriers and chains agree (the phases
        // differ by the reception's own sampling-time offset and CFO).
        double dot = 0, a = 0, b = 0;
        for (size_t i = 0; i < original->csi.size(); ++i)
        {
            const double x = std::abs(original->csi[i]), y = std::abs(ev.csi->csi[i]);
            dot += x * y, a += x * x, b += y * y;
        }
        EXPECT_GT(dot / std::sqrt(a * b), 0.8);
    }
    ASSERT_GT(frames, 100u);
    EXPECT_NEAR(double(retries) / double(frames), 0.3, 0.06);

    // Without the key: no retry.
    sc.impairments.retryProbability = 0;
    Simulator plain(sc);
    for (size_t guard = 0; guard < 100000 && plain.next(ev); ++guard)
    {
        if (ev.kind == SimEvent::Kind::Csi)
        {
            ASSERT_EQ(ev.frame.reception, 0u);
        }
    }
}

// A receiver with a channel schedule (issue 56.2) hears exactly the frames of the stream
// without one that fall inside a listening window of their transmitter's channel: nothing from
// another channel, nothing while it retunes, every channel in turn; odometry is unchanged.
TEST(Simulator, ReceiverScheduleHearsOnlyTheChannelItIsOn)
{
    Scenario sc = baseScenario();
    sc.impairments.retryProbability = 0.2;  // retries are heard (or not) like frames
    Simulator everyChannel(sc);
    sc.receiver.channelSchedule = {Chanspec::make(36, 20), Chanspec::make(155, 80)};
    sc.receiver.channelDwell_s = 0.4;
    sc.receiver.channelSwitch_s = 0.05;
    Simulator hopping(sc);

    const double slot = 0.45;
    const auto listening = [&](size_t tx, double t)
    {
        const auto k = size_t(std::floor(t / slot));
        return t - double(k) * slot < 0.4 &&
               sc.receiver.channelSchedule[k % 2].sameChannel(sc.transmitters[tx].chanspec);
    };
    std::vector<std::tuple<size_t, uint64_t, unsigned, double>> expected, heard;
    size_t odometryAll = 0, odometryHopping = 0;
    for (const SimEvent& ev : runAll(everyChannel))
        if (ev.kind == SimEvent::Kind::Odometry)
            ++odometryAll;
        else if (listening(ev.frame.transmitterIndex, ev.time_s))
            expected.emplace_back(
                ev.frame.transmitterIndex, ev.frame.frameIndex, ev.frame.reception, ev.time_s);
    std::set<size_t> slotsWithFrames;
    for (const SimEvent& ev : runAll(hopping))
    {
        if (ev.kind == SimEvent::Kind::Odometry)
        {
            ++odometryHopping;
            continue;
        }
        const size_t tx = ev.frame.transmitterIndex;
        EXPECT_TRUE(listening(tx, ev.time_s)) << "tx " << tx << " heard at " << ev.time_s;
        EXPECT_EQ(ev.csi->chanspec.centerChannel, sc.transmitters[tx].chanspec.centerChannel);
        heard.emplace_back(tx, ev.frame.frameIndex, ev.frame.reception, ev.time_s);
        slotsWithFrames.insert(size_t(std::floor(ev.time_s / slot)));
    }
    EXPECT_EQ(heard, expected);
    EXPECT_EQ(odometryHopping, odometryAll);
    // 3 s: slots 0..6, both channels, every visit heard.
    EXPECT_EQ(slotsWithFrames.size(), 7u);
    EXPECT_GT(expected.size(), 100u);
}
