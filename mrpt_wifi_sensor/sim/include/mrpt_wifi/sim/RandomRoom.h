/* mrpt_wifi — WiFi channel state information for MRPT.  */
#pragma once

#include <mrpt_wifi/sim/Scenario.h>

#include <cstdint>
#include <string>

namespace mrpt_wifi::sim
{
/** Seeds of the random rooms are split once and for all: estimators and their options are tuned
 *  on the development seeds only (1 ≤ seed < kFirstEvaluationSeed), accuracy is reported on the
 *  evaluation seeds (≥ kFirstEvaluationSeed), which no tuning has looked at. */
constexpr uint32_t kFirstEvaluationSeed = 1000;
inline bool isEvaluationSeed(uint32_t seed)
{
    return seed >= kFirstEvaluationSeed;
}

struct RandomRoomOptions
{
    double duration_s = 60.0;
    /** Folder holding rt-ac86u.yaml and ap-linear-{2,4}.yaml (share/arrays). */
    std::string arraysDir;
    /** The receiver (its array file in arraysDir, channel of the APs, CSI format):
     *  "rt-ac86u" (155/80, every bin) or "intel5300" (intel5300-linear-3.yaml, 159/40, the 30
     *  grouped subcarriers as int8). The room itself does not depend on it. */
    std::string receiver = "rt-ac86u";
    /** 0: the robot drives to random goals (random_walk). N > 0: it drives N laps of a
     *  rectangle 0.6–2 m inside the walls, clear of the furniture, at the drawn speed and turn
     *  rate, and duration_s is set to the N laps (drift correction needs revisits). Where every
     *  such concentric rectangle crosses the furniture (2 of seeds 1–1999), one inset per side
     *  (≥ 0.6 m, the loop ≥ 1.5 m across); a room with no clear loop throws. The room, APs,
     *  speed and turn rate are the same draws either way. */
    unsigned loopLaps = 0;
    /** The odometry's systematic errors (scenario keys `scale_error`, `yaw_scale_error`,
     *  `yaw_drift_deg_per_m`); the random room itself has none. */
    double odometryScaleError = 0, odometryYawScaleError = 0, odometryYawDrift_deg_per_m = 0;
    /** Access points (≥ 3). Those beyond the third are drawn from a stream of their own, so a
     *  seed keeps its room, first three APs and drive whatever the count. */
    int accessPoints = 3;
    /** Streams every AP sends: 0 draws one or two per AP (two from ap-linear-2.yaml); 2 or 4
     *  gives every AP that many from ap-linear-2.yaml or ap-linear-4.yaml (AoD at every AP).
     *  The draws are the same either way, so a seed keeps its room, APs and drive. */
    int accessPointStreams = 0;
};

/** The receivers randomRoomYaml() knows ("rt-ac86u", "intel5300"). */
bool isRandomRoomReceiver(const std::string& name);

/** A random office-like room as scenario YAML text (share/scenarios/README.md, "Random rooms",
 *  documents the distribution): a 6–14 × 5–10 m rectangle with walls of random reflectivity,
 *  rough walls (weak scatterers just in front of them), 1–3 clusters of 3–5 scatterers, 1–3
 *  pieces of furniture (attenuating segments with scattering edges), 3 access points (or
 *  options.accessPoints) near the walls facing into the room at random yaw (one or two
 *  streams), the robot's body shadowing one side of its receive array, and a robot that
 *  drives to random goals and stops at each for up to 4 s. Every draw is a function of the
 *  seed. */
std::string randomRoomYaml(uint32_t seed, const RandomRoomOptions& options = {});

/** The same, parsed (validated like any scenario file). */
Scenario randomRoomScenario(uint32_t seed, const RandomRoomOptions& options = {});

}  // namespace mrpt_wifi::sim
