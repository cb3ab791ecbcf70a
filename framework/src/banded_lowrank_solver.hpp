// A SUNDIALS direct linear solver for the Newton matrix of size-class populations that layer (solver.linear_solver:
// banded). Such a matrix is nearly banded once the states are ordered by size class: the growth scheme couples a
// class with a few neighbours, and zones that exchange particles couple class i of one with class i of the other.
// What is not banded is of low rank: the normalization of a layering growth rate by the total particle surface puts
// one outer product u v^T over a unit's classes, and the few states that are not per class (temperature, exchange and
// discharge rates) border the matrix with dense rows and columns. The solver
//  * reads the class structure from the units' declared class layouts (UnitSpec::set_classes),
//  * recovers each unit's outer product from the matrix itself (its entries between classes further apart than the
//    scheme's reach) and checks that it explains them all,
//  * factors the rest with SUNDIALS' band LU (SUNLinSol_Band, partial pivoting within the band) in the class-major
//    order, adds the outer products by Sherman-Morrison-Woodbury and the border by its Schur complement.
// When the matrix is not of that form (an aggregation kernel couples every class pair, a second growth law adds a
// second outer product) a setup factors it densely instead (Eigen's LU), so the result is right either way.
#pragma once
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

#include <vector>

namespace granuflow {
class DaeSystem;
}

namespace granuflow::detail {

// Per unknown its size class and its group (the unit whose classes one outer product may couple), -1 for the
// border (states not per class).
struct ClassStructure {
  std::vector<int> cls, group;
  int groups = 0;
  int reach = 3;  // classes further apart than this are coupled only through the outer product
};
ClassStructure class_structure(const DaeSystem& sys);

SUNLinearSolver make_banded_lowrank_solver(SUNContext ctx, ClassStructure s);
bool is_banded_lowrank_solver(SUNLinearSolver s);
// The next setup's matrix is the last setup's but on the diagonal (the integrator reuses a kept Jacobian at a new
// cj, jacobian_cache.hpp): the outer products and the band are not looked for again.
void banded_lowrank_same_but_diagonal(SUNLinearSolver s);
// A new segment of the run (a breakpoint, an event, a checkpoint): the setups start to look for the form afresh, as a
// run restarted from a checkpoint there does with a new solver, so that both take the same setups.
void banded_lowrank_new_segment(SUNLinearSolver s);
struct BandedLowRankStats {
  long setups = 0, dense_setups = 0;     // setups, and those factored densely (the structure did not hold)
  long untested_setups = 0;              // dense setups that did not look for it (it had failed in a row before)
  int lower = 0, upper = 0;              // band of the last banded setup
  int border = 0, rank = 0, states = 0;  // border states, outer products, unknowns
  double worst_outside = 0.0;            // largest |a_ij - u_i v_j| between distant classes, relative to max |a|
};
BandedLowRankStats banded_lowrank_stats(SUNLinearSolver s);

}  // namespace granuflow::detail
