// maglev-hil campaign: randomized fault runs on the bench, judged from the
// plant's own truth (docs/RELIABILITY.md "Fault campaign").
//
//   maglev-hil campaign --runs N [--start I] [--seed S] [--jobs J] [--out DIR] [--only I]
//
// Run i (seeded by S and i: reproducible alone with --only i) levitates the
// default stage, makes a random mix of the suite's motions, and meets one or
// two faults at random times with random durations and magnitudes: CAN
// (loss, burst loss, corruption, duplication, reordering, delay, a babbling
// node), sensors (beam loss, count jump, laser sensor out of range, Hall
// stuck, ADC railed or stuck, a stale sample), actuators (saturation, an
// amplifier open or shorted, gain drop, DAC stuck), the plant (a push, a
// payload added), power (a brown-out during a configuration save) and the
// host (a command storm, commands out of range).
//
// Unsafe outcomes, from the plant's truth, never from what the controller
// believes: a coil current beyond its rating; a touchdown faster than the
// profile's landing speed with the amplifiers on, or faster than the free
// fall from z_max with them off; the platen outside its travel; the stage
// still levitated 2 s after the controller latched a fault, or after a fault
// that must land it (beam loss, laser sensor out of range, ADC railed) went
// undetected; a configuration lost to a brown-out.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace maglev::bench {

// Fault kinds: name and category, defined once (names appear in the JSON).
#define MAGLEV_CAMPAIGN_FAULTS(X)                  \
  X(kCanLoss, "can_loss", "can")                   \
  X(kCanBurstLoss, "can_burst_loss", "can")        \
  X(kCanCorrupt, "can_corrupt", "can")             \
  X(kCanDuplicate, "can_duplicate", "can")         \
  X(kCanReorder, "can_reorder", "can")             \
  X(kCanDelay, "can_delay", "can")                 \
  X(kBabblingNode, "babbling_node", "can")         \
  X(kBeamLoss, "beam_loss", "sensor")              \
  X(kCountJump, "count_jump", "sensor")            \
  X(kLaserOutOfRange, "laser_out_of_range", "sensor") \
  X(kHallStuck, "hall_stuck", "sensor")            \
  X(kAdcRailed, "adc_railed", "sensor")            \
  X(kAdcStuck, "adc_stuck", "sensor")              \
  X(kStaleSample, "stale_sample", "sensor")        \
  X(kAmplifierSaturation, "amplifier_saturation", "actuator") \
  X(kAmplifierOpen, "amplifier_open", "actuator")  \
  X(kAmplifierShorted, "amplifier_shorted", "actuator") \
  X(kGainDrop, "gain_drop", "actuator")            \
  X(kDacStuck, "dac_stuck", "actuator")            \
  X(kPush, "push", "plant")                        \
  X(kPayloadAdded, "payload_added", "plant")       \
  X(kBrownoutDuringSave, "brownout_during_save", "power") \
  X(kCommandStorm, "command_storm", "host")        \
  X(kCommandOutOfRange, "command_out_of_range", "host") \
  X(kConfigWrite, "config_write", "host")

enum class CampaignFault : std::uint8_t {
#define MAGLEV_CAMPAIGN_ENUM(name, text, category) name,
  MAGLEV_CAMPAIGN_FAULTS(MAGLEV_CAMPAIGN_ENUM)
#undef MAGLEV_CAMPAIGN_ENUM
      kCount
};
const char* to_string(CampaignFault f);
const char* category_of(CampaignFault f);

struct FaultEvent {
  CampaignFault kind = CampaignFault::kCanLoss;
  double t_s = 0.0;
  double duration_s = 0.0;
  double magnitude = 0.0;  // kind-specific (see campaign.cpp: MakePlan)
  int target = 0;          // frame kind, sensor, coil or axis index
};

struct CampaignPlan {
  std::uint64_t run_seed = 0;
  std::vector<std::string> motions;  // timeline lines after levitation
  std::vector<FaultEvent> faults;
};

// The plan of run `index` of a campaign seeded `seed` (deterministic).
CampaignPlan MakePlan(std::uint64_t seed, int index);

struct CampaignOptions {
  int runs = 100;
  std::uint64_t seed = 1;
  int jobs = 1;
  int only = -1;        // >= 0: run this index alone
  int start = 0;        // first run index (runs start .. start + runs - 1)
  std::string out_dir;  // campaign.json when set
  bool verbose = false;
};

int campaign_main(int argc, char** argv);

}  // namespace maglev::bench
