// A SUNDIALS direct linear solver for the Newton matrix of size-class populations whose pair processes couple every
// class with every other (solver.linear_solver: class_local). Aggregation and breakage make that matrix dense, but
// over the steps the integrator takes those couplings are weak against each class's own terms (moisture, heat,
// growth of that class): the Newton iteration converges at nearly the same rate without them. The solver therefore
// factors an approximation of the Newton matrix,
//  * one dense block per size class (the states of class i of every unit with classes: a bed's mass and water),
//  * the border (the states that are not per class: temperatures, gas, rates) in full, rows and columns,
// and leaves out the entries between two different classes, but for one outer product per conserved class block
// (DaeSystem::conserved_blocks: a bed's mass and water): the column sums over the block of everything left out,
// spread over its rows in proportion to what each class holds, so that every Newton correction changes the block's
// total exactly as the exact matrix's would and puts nothing into an empty class (spread evenly, it took the empty
// top classes of a wide grid below zero). The pair processes only move mass between classes: without this term the
// run's solids balance closed to 1e-6 (80 classes) or 1e-5 (193), against 1e-15 with the exact matrix. The residual,
// and so the solution the Newton iteration converges to and the integrator's error test, are untouched; only the number
// of iterations can change. A setup costs the blocks' small LUs and a Schur complement on the border, a solve
// O(states): no dense LU. While the integrator computes consistent initial values (whole(true)) it factors the whole
// matrix with Eigen's LU, since a Newton iteration started from a guess needs the exact matrix.
#pragma once
#include <sundials/sundials_context.h>
#include <sundials/sundials_linearsolver.h>

#include <functional>
#include <vector>

#include "banded_lowrank_solver.hpp"

namespace granuflow::detail {

// What the solver reads besides the matrix: the class structure, the conserved blocks (each a list of unknowns) and,
// per block, the column sums over its rows of what the last class-local Jacobian's units left out (n values; null:
// nothing). class_local_source(sys): the system's (class_structure, DaeSystem::conserved_blocks, left_out); `sys`
// must outlive the solver.
struct ClassLocalSource {
  ClassStructure st;
  std::vector<std::vector<int>> blocks;
  std::function<const double*(int)> left_out;
  std::function<const double*()> at;  // the unknowns at that Jacobian (null: spread evenly)
};
ClassLocalSource class_local_source(const DaeSystem& sys);
SUNLinearSolver make_class_local_solver(SUNContext ctx, ClassLocalSource src);
bool is_class_local_solver(SUNLinearSolver s);
// Factor the whole matrix (true) or its class-local part (false) from the next setup on.
void class_local_whole(SUNLinearSolver s, bool whole);
// The next setup's matrix is the last setup's but on the diagonal (a kept Jacobian at a new cj).
void class_local_same_but_diagonal(SUNLinearSolver s);
struct ClassLocalStats {
  long setups = 0, whole_setups = 0;   // setups, and those that factored the whole matrix
  int classes = 0, largest_block = 0;  // per-class blocks and the largest of them
  int border = 0, states = 0;          // border states, unknowns
};
ClassLocalStats class_local_stats(SUNLinearSolver s);

}  // namespace granuflow::detail
