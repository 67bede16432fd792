#pragma once
// Which encoders there are: the host's side of the encoder list (cl/encoders.h). The enum, the
// table and every name come from that list; how an encoder's keys are made is its family's
// (encode/encoder_family.h).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "encoders.h"
#include "keys.h"

namespace raysort {

// Encoder::<Host> = RS_ENC_<ID>, one per row of the list, NoSort first. Values from RS_ENC_COUNT on
// are encoders from files, loaded at run time (encode/encoder_file.h).
enum class Encoder : int {
#define RS_HOST_ENUM(ID, HOST, NAME, FAMILY_OR_CODE, WEIGHT, ALIASES) HOST = RS_ENC_##ID,
  RS_ENCODERS(RS_HOST_ENUM, RS_HOST_ENUM)
#undef RS_HOST_ENUM
};

class EncoderFamily;

// One row of the encoder table, made from the encoder list's row.
struct EncoderInfo {
  Encoder id;
  std::string_view name;                  // as the CLI and result sets spell it
  std::vector<std::string_view> aliases;  // other spellings parse_encoder accepts
  const EncoderFamily* family;            // how its keys are made (encode/encoder_family.h)
  std::string_view family_name;           // the list's family token: "spatial", "box_set", ...
  std::string_view kernel;                // its cl/encode.cl kernel, without the _k32 / _k64 suffix
  unsigned cost_weight_pct;               // encode + sort on top of a trace, % (the shard planner's cost)
};

// Every encoder of the list, NoSort first, in the order of the enum.
const std::vector<EncoderInfo>& encoder_table();
// The row of any encoder: the list's, or an encoder from a file's (ids past RS_ENC_COUNT).
const EncoderInfo& encoder_info(Encoder e);
const EncoderFamily& encoder_family(Encoder e);

// "nosort", "origin", "reis", "costa", "aila", "twopoint", "grid", "hcc", "mlhcc", "ppc", "hcc-dir",
// "hcc-region", "hcc-traffic", "mlhcc-cost".
std::string_view encoder_name(Encoder e);
// Case-insensitive, ignoring '-', '_' and spaces; also accepts the table's aliases, and the name
// "file:<stem>" of an encoder from a file already loaded (exactly as spelled).
std::optional<Encoder> parse_encoder(std::string_view name);
// Every encoder, NoSort first, in the order of the enum.
const std::vector<Encoder>& all_encoders();
// A command line's encoder list: names or aliases, file:PATH (an encoder from a file, loaded here:
// encode/encoder_file.h), or {"all"}. Throws Error naming an unknown one and listing the encoders.
std::vector<Encoder> parse_encoders(const std::vector<std::string>& names);
// The widest key an encoder supports (64 for all of them today).
unsigned max_key_bits(Encoder e);

}  // namespace raysort
