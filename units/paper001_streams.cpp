#include "paper001_streams.hpp"

namespace granuflow::units::paper001 {

StreamKind holdup_stream() {
  static const StreamType t{"holdup", "a bed's state: per class dry-solid and water mass, temperature, gas velocity",
                            [](int n) {
                              return holdup_field_specs(n, {"u0", "m/s"});
                            }};
  return &t;
}

StreamKind wetting_stream() {
  static const StreamType t{"wetting",
                            "spray zone -> bed per class: deposited liquid, wetted fraction, wet-spot moisture; then T",
                            [](int n) {
                              std::vector<FieldSpec> f;
                              append_class_fields(f, "mdot", n, "kg/s");
                              append_class_fields(f, "fwet", n, "-");
                              append_class_fields(f, "Xwet", n, "kg/kg");
                              f.push_back({"T", "K"});
                              return f;
                            }};
  return &t;
}

}  // namespace granuflow::units::paper001
