#include "classification/separation_curves.hpp"

namespace granuflow::kernels {

void register_separation_curves(Registry<SeparationCurve>& r) {
  r.add("sharp", "ideal screen: everything above d_cut to the coarse side",
        [] { return std::make_unique<SharpCut>(); });
  r.add("plitt", "T = 1 - exp(-ln 2 (d/d_cut)^m) (Plitt 1976)", [] { return std::make_unique<PlittCurve>(); });
  r.add("molerus_hoffmann", "T = 1 / (1 + (d_cut/d)^2 exp(k (1 - (d/d_cut)^2))) (Molerus & Hoffmann 1969)",
        [] { return std::make_unique<MolerusHoffmannCurve>(); });
}

}  // namespace granuflow::kernels
