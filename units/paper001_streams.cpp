#include "paper001_streams.hpp"

#include <string>

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
                            "spray zone -> bed per class: deposited liquid, wetted fraction, wet-spot moisture; then "
                            "T, the solids fraction w of the deposit and the residence-time fraction at the n + 1 "
                            "cell faces",
                            [](int n) {
                              std::vector<FieldSpec> f;
                              append_class_fields(f, "mdot", n, "kg/s");
                              append_class_fields(f, "fwet", n, "-");
                              append_class_fields(f, "Xwet", n, "kg/kg");
                              f.push_back({"T", "K"});
                              f.push_back({"w", "kg/kg"});
                              for (int k = 0; k <= n; ++k) f.push_back({"tau_face_" + std::to_string(k), "-"});
                              return f;
                            }};
  return &t;
}

}  // namespace granuflow::units::paper001
