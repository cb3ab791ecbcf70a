// The serial N_Vector's arithmetic compiled with the project's optimization flags, installed into a vector's operation
// table (which its clones copy). Debian's SUNDIALS 6.4.1 packages are built without optimization (-O0: every loop
// variable lives on the stack), so a vector operation there costs about 1 ns per element and the integrators'
// bookkeeping outweighed the right-hand side of a 100-class population balance (a quarter of an explicit Runge-Kutta
// run in N_VLinearCombination alone). The replacements keep the documented semantics of each operation (SUNDIALS
// user guide, "Description of the NVECTOR operations"), aliasing of arguments included; only the vector layout of
// the serial implementation (contiguous data, N_VGetLength) is relied on.
#pragma once
#include <sundials/sundials_nvector.h>

namespace granuflow::detail {

// Replaces the arithmetic, reduction and fused operations of serial vector v (creation, cloning and access stay the
// library's). Fused operations are switched on as well.
void install_serial_vector_ops(N_Vector v);

}  // namespace granuflow::detail
