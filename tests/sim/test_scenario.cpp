/* mrpt_wifi — WiFi channel state information for MRPT.
 *
 * Scenario files: the samples in share/ load and simulate; bad input is reported with the file,
 * line and key. */
#include <gtest/gtest.h>
#include <mrpt/system/CDirectoryExplorer.h>
#include <mrpt/system/filesystem.h>
#include <mrpt_wifi/sim/Simulator.h>

#include <cmath>
#include <fstream>
#include <set>

#include "TestSupport.h"

using namespace mrpt_wifi;
using namespace mrpt_wifi::sim;

namespace
{
const std::string kShare = std::string(MRPT_WIFI_SOURCE_DIR) + "/share";

// A small valid scenario; tests break one thing at a time. Line numbers matter below.
const std::string kValid = R"(name: test
duration_s: 2
seed: 3
room:
  corners: [[0, 0], [10, 0], [10, 5], [0, 5]]
transmitters:
  - name: a
    mac: '02:00:00:00:00:01'
    position: [1, 1]
    channel: 155/80
  - name: b
    mac: '02:00:00:00:00:02'
    position: [9, 4]
    channel: 36/20
receiver:
  array:
    elements: [[0, 0], [0, 0.026]]
motion:
  type: waypoints
  start: [5, 2.5, 90]
  waypoints: [[6, 3]]
)";

std::string replaced(std::string text, const std::string& from, const std::string& to)
{
    const auto pos = text.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    if (pos != std::string::npos) text.replace(pos, from.size(), to);
    return text;
}

/** Loads a text expected to fail; returns the error. */
ScenarioError loadError(const std::string& text)
{
    try
    {
        Scenario::fromYamlText(text, "bad.yaml", kShare + "/scenarios");
    }
    catch (const ScenarioError& e)
    {
        return e;
    }
    ADD_FAILURE() << "no error for:\n" << text;
    return ScenarioError("", 0, "", "");
}
}  // namespace

TEST(Scenario, ValidTextLoads)
{
    const Scenario sc = Scenario::fromYamlText(kValid, "ok.yaml");
    EXPECT_EQ(sc.name, "test");
    ASSERT_EQ(sc.transmitters.size(), 2u);
    EXPECT_EQ(sc.transmitters[1].chanspec, Chanspec::make(36, 20));
    EXPECT_EQ(sc.transmitters[0].mac.asString(), "02:00:00:00:00:01");
    EXPECT_EQ(sc.walls.size(), 4u);
    EXPECT_EQ(sc.receiver.array.size(), 2u);
    EXPECT_NEAR(sc.motion.start.phi, M_PI / 2, 1e-12);
    EXPECT_EQ(sc.motion.type, MotionType::Waypoints);
}

TEST(Scenario, RtAc86uArrayFileHasTheDesignGeometry)
{
    const auto a = AntennaArray::fromYamlFile(kShare + "/arrays/rt-ac86u.yaml");
    ASSERT_EQ(a.size(), 4u);
    const double y[4] = {0.0, 0.052, 0.026, 0.078};
    for (size_t i = 0; i < 4; ++i)
    {
        EXPECT_DOUBLE_EQ(a.elements[i].x, 0.0);
        EXPECT_DOUBLE_EQ(a.elements[i].y, y[i]);
    }
    EXPECT_EQ(AntennaArray::fromYamlFile(kShare + "/arrays/square-2x2.yaml").size(), 4u);
}

TEST(Scenario, UnknownTopLevelKeyNamesKeyAndLine)
{
    const auto e = loadError(replaced(kValid, "seed: 3", "sede: 3"));
    EXPECT_EQ(e.keyPath(), "sede");
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find("bad.yaml:3: sede: unknown key 'sede'"), std::string::npos)
        << e.what();
}

TEST(Scenario, UnknownNestedKeyNamesKeyPathAndLine)
{
    const auto e = loadError(replaced(kValid, "    channel: 36/20", "    chanel: 36/20"));
    EXPECT_EQ(e.keyPath(), "transmitters[1].chanel");
    EXPECT_EQ(e.line(), 14);
    EXPECT_NE(std::string(e.what()).find("allowed here"), std::string::npos);
}

TEST(Scenario, TransmitterOutsideTheRoom)
{
    const auto e = loadError(replaced(kValid, "position: [9, 4]", "position: [12, 4]"));
    EXPECT_EQ(e.keyPath(), "transmitters[1].position");
    EXPECT_EQ(e.line(), 13);
    EXPECT_NE(std::string(e.what()).find("outside the room"), std::string::npos) << e.what();
}

TEST(Scenario, ImpossibleChannels)
{
    for (const char* ch : {"200/80", "6/80", "155/160", "6/160", "abc", "155/"})
    {
        const auto e =
            loadError(replaced(kValid, "channel: 155/80", std::string("channel: ") + ch));
        EXPECT_EQ(e.keyPath(), "transmitters[0].channel") << ch;
        EXPECT_EQ(e.line(), 10) << ch;
        EXPECT_NE(std::string(e.what()).find("impossible channel"), std::string::npos) << e.what();
    }
}

TEST(Scenario, BadValuesNameTheirKey)
{
    auto e = loadError(replaced(kValid, "duration_s: 2", "duration_s: two"));
    EXPECT_EQ(e.keyPath(), "duration_s");
    EXPECT_EQ(e.line(), 2);
    e = loadError(replaced(kValid, "duration_s: 2", "duration_s: -1"));
    EXPECT_EQ(e.keyPath(), "duration_s");
    EXPECT_EQ(e.line(), 2);
    e = loadError(replaced(kValid, "'02:00:00:00:00:02'", "'02:00:00:00:00'"));
    EXPECT_EQ(e.keyPath(), "transmitters[1].mac");
    e = loadError(replaced(kValid, "'02:00:00:00:00:02'", "'02:00:00:00:00:01'"));
    EXPECT_EQ(e.keyPath(), "transmitters[1].mac");
    EXPECT_NE(std::string(e.what()).find("duplicate"), std::string::npos);
    e = loadError(replaced(kValid, "waypoints: [[6, 3]]", "waypoints: [[6, 30]]"));
    EXPECT_EQ(e.keyPath(), "motion.waypoints[0]");
    EXPECT_EQ(e.line(), 21);
    e = loadError(replaced(
        kValid, "motion:", "obstacles:\n  - {name: crate, from: [5.5, 2], to: [5.5, 4]}\nmotion:"));
    EXPECT_EQ(e.keyPath(), "motion.waypoints[0]");  // start → waypoint 0 crosses the crate
    EXPECT_NE(std::string(e.what()).find("crosses obstacle 'crate'"), std::string::npos);
    e = loadError(replaced(kValid, "type: waypoints", "type: teleport"));
    EXPECT_EQ(e.keyPath(), "motion.type");
    e = loadError(replaced(kValid, "name: b\n", "name: b\n    streams: 2\n"));
    EXPECT_EQ(e.keyPath(), "transmitters[1].array");  // 2 streams need 2 elements
}

TEST(Scenario, MissingRequiredKeyAndMissingArrayFile)
{
    auto e = loadError(replaced(kValid, "    mac: '02:00:00:00:00:01'\n", ""));
    EXPECT_EQ(e.keyPath(), "transmitters[0]");
    EXPECT_NE(std::string(e.what()).find("missing required key 'mac'"), std::string::npos);
    e = loadError(replaced(
        kValid, "  array:\n    elements: [[0, 0], [0, 0.026]]", "  array: ../arrays/nope.yaml"));
    EXPECT_EQ(e.keyPath(), "receiver.array");
    EXPECT_EQ(e.line(), 16);
    EXPECT_NE(std::string(e.what()).find("nope.yaml"), std::string::npos);
}

TEST(Scenario, YamlSyntaxErrorNamesTheFile)
{
    const auto e = loadError("name: [unclosed\nseed: 1\n");
    EXPECT_EQ(e.file(), "bad.yaml");
}

TEST(Scenario, FromFileReportsTheFileName)
{
    const std::string path = mrpt_wifi::test::tempPath() + ".yaml";
    std::ofstream(path) << replaced(kValid, "seed: 3", "seed: 3\nbogus: 1");
    try
    {
        Scenario::fromYamlFile(path);
        FAIL() << "no error";
    }
    catch (const ScenarioError& e)
    {
        EXPECT_EQ(e.file(), path);
        EXPECT_EQ(e.line(), 4);
        EXPECT_NE(std::string(e.what()).find(path + ":4: bogus"), std::string::npos) << e.what();
    }
    mrpt::system::deleteFile(path);
    EXPECT_THROW(Scenario::fromYamlFile("/nonexistent/scenario.yaml"), ScenarioError);
}

// Every sample in share/scenarios loads and simulates a few seconds with frames from every
// transmitter and odometry.
TEST(Scenario, SampleScenariosLoadAndSimulate)
{
    const std::vector<std::string> names{
        "calibration",
        "bearing",
        "kidnapped",
        "iot",
        "loop",
        "roaming",
        "calibration-2g4",
        "hopping",
        "building",
        "building-hopping",
        "building-hopping-receiver"};
    for (const auto& name : names)
    {
        SCOPED_TRACE(name);
        Scenario sc = Scenario::fromYamlFile(kShare + "/scenarios/" + name + ".yaml");
        EXPECT_EQ(sc.name, name);
        sc.duration_s = 2.0;
        Simulator sim(sc);
        std::vector<unsigned> frames(sc.transmitters.size(), 0);
        unsigned odometry = 0;
        SimEvent ev;
        while (sim.next(ev))
        {
            if (ev.kind == SimEvent::Kind::Odometry)
                ++odometry;
            else
            {
                ++frames[ev.frame.transmitterIndex];
                ASSERT_TRUE(ev.csi->isComplete());
                EXPECT_GT(ev.frame.snr_dB, 0.0);
            }
        }
        for (size_t i = 0; i < frames.size(); ++i)
        {
            // A hopping receiver hears each transmitter only while on its channel.
            double listening_s = 0;
            for (double t = 0.0005; t < 2.0; t += 0.001)
                listening_s +=
                    0.001 * (sc.receiver.nextListeningTime(sc.transmitters[i].chanspec, t) == t);
            EXPECT_NEAR(frames[i], listening_s * sc.transmitters[i].frameRate_Hz, 1.0) << i;
        }
        EXPECT_EQ(odometry, unsigned(2.0 * sc.odometry.rate_Hz) + 1);
    }
    // ... and nothing else is lying there untested.
    const auto files =
        mrpt::system::CDirectoryExplorer::explore(kShare + "/scenarios", FILE_ATTRIB_ARCHIVE);
    unsigned yamls = 0;
    for (const auto& f : files)
        yamls += f.name.size() > 5 && f.name.substr(f.name.size() - 5) == ".yaml";
    EXPECT_EQ(yamls, names.size());
}

TEST(Scenario, JumpStatesLimitedToAllowedOnesUntilATime)
{
    // A calibration drive that never visits a state (issue 53.1): until allowed_until_s every
    // chain stays within allowed_states, then it may take any.
    const std::string jumps =
        "impairments:\n  antenna_jumps: {enabled: true, states: 3, "
        "rate_hz: 2, allowed_states: [0, 1], allowed_until_s: 20}\n";
    Scenario sc = Scenario::fromYamlText(kValid + jumps, "jumps.yaml", kShare + "/scenarios");
    ASSERT_EQ(sc.impairments.jumpAllowedStates, (std::vector<unsigned>{0, 1}));
    EXPECT_EQ(sc.impairments.jumpAllowedUntil_s, 20.0);
    const HardwareModel hw(sc.impairments, 4, sc.seed, 0, 60);
    for (unsigned rx = 1; rx < 4; ++rx)
    {
        size_t before = 0, stateTwoAfter = 0;
        for (const auto& e : hw.jumpEvents(rx))
        {
            if (e.time_s < 20)
            {
                ++before;
                EXPECT_LE(e.state, 1) << "chain " << rx << " at " << e.time_s << " s";
            }
            else
                stateTwoAfter += e.state == 2;
        }
        EXPECT_GT(before, 10u) << "chain " << rx;
        EXPECT_GT(stateTwoAfter, 0u) << "chain " << rx << ": state 2 never taken afterwards";
    }
    // The same timeline as before the option when it is not given.
    Scenario plain = Scenario::fromYamlText(
        kValid + "impairments:\n  antenna_jumps: {enabled: true, states: 3, rate_hz: 2}\n",
        "plain.yaml", kShare + "/scenarios");
    const HardwareModel unrestricted(plain.impairments, 4, plain.seed, 0, 60);
    size_t stateTwoEarly = 0;
    for (const auto& e : unrestricted.jumpEvents(1)) stateTwoEarly += e.time_s < 20 && e.state == 2;
    EXPECT_GT(stateTwoEarly, 0u);

    auto e = loadError(kValid + replaced(jumps, "[0, 1]", "[0, 3]"));
    EXPECT_EQ(e.keyPath(), "impairments.antenna_jumps.allowed_states[1]");
    e = loadError(kValid + replaced(jumps, "allowed_until_s: 20", "allowed_until_s: -1"));
    EXPECT_EQ(e.keyPath(), "impairments.antenna_jumps.allowed_until_s");
}

TEST(Scenario, JumpStatesOfRealSizeFromListedDelays)
{
    // Issue 54: the states a real RT-AC86U shows at 20 MHz (one 80 MHz sample apart, sample
    // slips); their count is the list's, a different `states` is refused with its key.
    const std::string jumps =
        "impairments:\n  antenna_jumps: {enabled: true, state_delays_ns: [-20.9, -9.0, 4.1, "
        "16.0], baseband: true, rate_hz: 0.5}\n";
    Scenario sc = Scenario::fromYamlText(kValid + jumps, "real.yaml", kShare + "/scenarios");
    EXPECT_EQ(sc.impairments.jumpStates, 4u);
    ASSERT_EQ(sc.impairments.jumpStateDelays_s.size(), 4u);
    EXPECT_NEAR(sc.impairments.jumpStateDelays_s[0], -20.9e-9, 1e-15);
    EXPECT_TRUE(sc.impairments.jumpBaseband);
    const HardwareModel hw(sc.impairments, 4, sc.seed, 0, 60);
    EXPECT_NEAR(hw.jumpStateDelay_s(3), 16.0e-9, 1e-15);
    EXPECT_EQ(hw.jumpDelay_s(0, 30), 0.0);
    std::set<uint8_t> visited;
    for (const auto& e : hw.jumpEvents(1)) visited.insert(e.state);
    EXPECT_EQ(visited.size(), 4u);

    auto e = loadError(kValid + replaced(jumps, "enabled: true,", "enabled: true, states: 3,"));
    EXPECT_EQ(e.keyPath(), "impairments.antenna_jumps.state_delays_ns");
    e = loadError(kValid + replaced(jumps, "[-20.9, -9.0, 4.1, 16.0]", "[]"));
    EXPECT_EQ(e.keyPath(), "impairments.antenna_jumps.state_delays_ns");
}

TEST(Scenario, ReceiverChannelScheduleKeysAndTheirErrors)
{
    const auto withSchedule = [](const std::string& keys)
    { return replaced(kValid, "receiver:\n", "receiver:\n" + keys); };
    const Scenario sc = Scenario::fromYamlText(
        withSchedule("  channel_schedule: [155/80, 36/20]\n  channel_dwell_s: 0.5\n"
                     "  channel_switch_ms: 50\n"),
        "hop.yaml", kShare + "/scenarios");
    ASSERT_EQ(sc.receiver.channelSchedule.size(), 2u);
    EXPECT_TRUE(sc.receiver.channelSchedule[0].sameChannel(sc.transmitters[0].chanspec));
    EXPECT_TRUE(sc.receiver.channelSchedule[1].sameChannel(sc.transmitters[1].chanspec));
    EXPECT_DOUBLE_EQ(sc.receiver.channelDwell_s, 0.5);
    EXPECT_DOUBLE_EQ(sc.receiver.channelSwitch_s, 0.05);
    // Listening on 36/20 during [0.55, 1.05) of every 1.1 s cycle.
    const Chanspec ch36 = sc.transmitters[1].chanspec;
    EXPECT_DOUBLE_EQ(sc.receiver.nextListeningTime(ch36, 0.2), 0.55);
    EXPECT_DOUBLE_EQ(sc.receiver.nextListeningTime(ch36, 0.7), 0.7);
    EXPECT_DOUBLE_EQ(sc.receiver.nextListeningTime(ch36, 1.07), 1.65);
    EXPECT_TRUE(std::isinf(sc.receiver.nextListeningTime(Chanspec::make(100, 20), 0.1)));
    // Without the keys: every channel at once, the emulator's retune time as the default.
    const Scenario plain = Scenario::fromYamlText(kValid, "plain.yaml", kShare + "/scenarios");
    EXPECT_TRUE(plain.receiver.channelSchedule.empty());
    EXPECT_DOUBLE_EQ(plain.receiver.channelSwitch_s, 0.020);
    EXPECT_DOUBLE_EQ(plain.receiver.nextListeningTime(ch36, 0.2), 0.2);

    struct Bad
    {
        std::string keys, keyPath, says;
    };
    for (const Bad& b : std::vector<Bad>{
             {"  channel_schedule: [155/80, 100/20]\n", "receiver.channel_schedule[1]",
              "no transmitter is on 100/20"},
             {"  channel_schedule: [155/80, 155/80]\n", "receiver.channel_schedule[1]",
              "already in the schedule"},
             {"  channel_schedule: [155/8]\n", "receiver.channel_schedule[0]",
              "impossible channel"},
             {"  channel_schedule: []\n", "receiver.channel_schedule", "expected a list"},
             {"  channel_schedule: [155/80]\n  channel_dwell_s: 0\n", "receiver.channel_dwell_s",
              "must be > 0"},
             {"  channel_schedule: [155/80]\n  channel_switch_ms: -5\n",
              "receiver.channel_switch_ms", "must be >= 0"},
         })
    {
        SCOPED_TRACE(b.keys);
        const auto e = loadError(withSchedule(b.keys));
        EXPECT_EQ(e.keyPath(), b.keyPath);
        EXPECT_NE(std::string(e.what()).find(b.says), std::string::npos) << e.what();
        EXPECT_GT(e.line(), 0);
    }
}
