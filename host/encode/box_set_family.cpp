// The box-set family: HCC, RegularGrid, HCC_DIR and hcc-traffic (see box_set_family.h).
#include "encode/box_set_family.h"

#include <map>

#include "bvh/cut.h"
#include "encode/cut_tables.h"
#include "keys_spatial.h"
#include "trace/tracer.h"
#include "util/error.h"

namespace raysort {

namespace {

// One box-set encoder's inputs per key length, and hcc-traffic's traffic.
struct BoxSetState : EncoderState {
  std::map<unsigned, std::vector<RsBox>> boxes;
  std::map<unsigned, CutSet> sets;
  std::vector<std::uint64_t> traffic;
  std::map<unsigned, std::vector<std::uint32_t>> traffic_cuts;
};

class BoxSetFamily final : public EncoderFamily {
 public:
  std::string key_bits_problem(Encoder e, unsigned bits, const EncoderParams& params) const override {
    if (e == Encoder::HCC_DIR) {
      if (params.direction_bits > 2 * RS_DIRECTION_LEVELS)
        return "hcc-dir takes at most " + std::to_string(2 * RS_DIRECTION_LEVELS) + " direction bits, not " +
               std::to_string(params.direction_bits);
      if (params.direction_bits >= bits)
        return "hcc-dir with " + std::to_string(params.direction_bits) + " direction bits needs keys of more than " +
               std::to_string(params.direction_bits) + " bits, not " + std::to_string(bits);
    }
    if (e == Encoder::HCC_TRAFFIC && !(params.traffic_blend >= 0.0 && params.traffic_blend <= 1.0))
      return "hcc-traffic's traffic blend (--traffic-blend) is a number from 0 (HAD only) to 1 (traffic only), not " +
             std::to_string(params.traffic_blend);
    return "";
  }

  HostKey host_key(Encoder e, unsigned bits, const EncodeScene& scene) const override {
    const CutSet& set = cut_set(scene, e, bits);
    const unsigned dir = direction_bits(e, scene);
    return [&set, bits, dir](const RsRay& ray) {
      return rs_key_from_code(rs_box_set_code(ray, set.groups.data(), set.box_count, bits - dir, dir), bits);
    };
  }

  std::vector<KernelArg> upload(Encoder e, unsigned bits, const EncodeScene& scene, DeviceUploads& up) const override {
    const CutSet& set = cut_set(scene, e, bits);
    return {up.buffer("cut boxes", set.groups), set.box_count};
  }

  std::vector<std::string> extra_kernels() const override { return {"encode_box_set_or", "encode_direction"}; }

  // HCC_DIR with more than one direction bit runs two kernels: the direction bits first (atan2,
  // acos; cl/encode.cl, encode_direction), then the box bits ORed in. One direction bit comes from
  // the signs of dx and dy (keys_spatial.h, rs_direction_top_bit) in the box-set kernel itself.
  EncodeEvents enqueue(const EncodeLaunch& l) const override {
    const cl_uint dir = direction_bits(l.encoder, l.scene), field = l.bits - dir;
    std::vector<KernelArg> args = l.inputs;
    args.push_back(field);
    if (dir <= 1) {
      args.push_back(dir);
      cl::Kernel& k = l.kernel("encode_box_set");
      l.set_args(k, args);
      const cl::Event ev = l.launch(k, l.count);
      return {ev, ev};
    }
    EncodeEvents ev;
    cl_call("encoding the direction bits of " + std::to_string(l.count) + " rays (HCC_DIR, " + std::to_string(l.bits) +
                " bits)",
            [&] {
              cl::Kernel& kd = l.kernel("encode_direction");
              cl_uint arg = 0;
              for (const cl::Buffer* b : {&l.rays, &l.order}) kd.setArg(arg++, *b);
              for (cl_uint v : {cl_uint(l.count), field, dir, cl_uint(l.bits)}) kd.setArg(arg++, v);
              kd.setArg(arg++, l.keys);
              kd.setArg(arg++, l.values);
              ev.first = l.launch(kd, l.count);
            });
    args.push_back(0u);  // the direction bits are in keys already: OR in the box field
    cl::Kernel& k = l.kernel("encode_box_set_or");
    l.set_args(k, args);
    ev.last = l.launch(k, l.count);
    return ev;
  }

  LearnsFrom learns_from(Encoder e) const override {
    return e == Encoder::HCC_TRAFFIC ? LearnsFrom::EarlierBatch : LearnsFrom::Nothing;
  }
  std::shared_ptr<const LearnedInput> study(Encoder e, const EncodeScene& scene, const RayBatch& before) const override {
    if (e != Encoder::HCC_TRAFFIC) return nullptr;
    auto learned = std::make_shared<NodeTraffic>();
    learned->visits = node_traffic(scene.bvh(), before.rays, before.any_hit());
    return learned;
  }
  void use(Encoder e, const LearnedInput* learned, EncodeScene& scene) const override {
    if (e != Encoder::HCC_TRAFFIC) return;
    set_node_traffic(scene, learned ? dynamic_cast<const NodeTraffic&>(*learned).visits : std::vector<std::uint64_t>{});
  }

 private:
  static unsigned direction_bits(Encoder e, const EncodeScene& scene) {
    return e == Encoder::HCC_DIR ? scene.params().direction_bits : 0u;
  }
};

}  // namespace

const EncoderFamily& encoder_family_box_set() {
  static const BoxSetFamily family;
  return family;
}

const std::vector<RsBox>& box_set(const EncodeScene& scene, Encoder e, unsigned bits) {
  return cached_inputs(scene.state<BoxSetState>(e).boxes, bits, [&] {
    check_key_bits(e, bits, scene.params());
    std::vector<RsBox> boxes;
    auto add_nodes = [&](const std::vector<std::uint32_t>& cut) {
      for (std::uint32_t n : cut) boxes.push_back(to_rs_box(node_box(scene.bvh().nodes[n])));
    };
    if (e == Encoder::RegularGrid) {
      for (const Aabb& c : regular_grid_cells(scene.box(), bits)) boxes.push_back(to_rs_box(c));
    } else if (e == Encoder::HCC || e == Encoder::HCC_DIR) {
      add_nodes(scene.hcc_cut(e == Encoder::HCC ? bits : bits - scene.params().direction_bits));
    } else if (e == Encoder::HCC_TRAFFIC) {
      add_nodes(traffic_cut(scene, bits));
    } else {
      throw Error(std::string(encoder_name(e)) + " is not a box-set encoder");
    }
    return boxes;
  });
}

const CutSet& cut_set(const EncodeScene& scene, Encoder e, unsigned bits) {
  return cached_inputs(scene.state<BoxSetState>(e).sets, bits, [&] {
    const auto& boxes = box_set(scene, e, bits);
    return CutSet{rs_cut_groups(boxes.data(), boxes.size()), static_cast<rs_u32>(boxes.size())};
  });
}

void set_node_traffic(EncodeScene& scene, std::vector<std::uint64_t> visits) {
  if (!visits.empty() && visits.size() != scene.bvh().nodes.size())
    throw Error("node traffic for " + std::to_string(visits.size()) + " nodes, the BVH has " +
                std::to_string(scene.bvh().nodes.size()));
  scene.renew_state<BoxSetState>(Encoder::HCC_TRAFFIC).traffic = std::move(visits);
}

const std::vector<std::uint32_t>& traffic_cut(const EncodeScene& scene, unsigned size) {
  BoxSetState& state = scene.state<BoxSetState>(Encoder::HCC_TRAFFIC);
  return cached_inputs(state.traffic_cuts, size, [&] {
    const std::vector<double> priority = traffic_priority(scene.had(), state.traffic, scene.params().traffic_blend);
    return priority_cut(scene.bvh(), priority, size, 0, &scene.had());
  });
}

}  // namespace raysort
