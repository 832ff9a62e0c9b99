// Closed-form IK from a DH table: every position solution of a 3-joint chain
// (3R and its prismatic variants) and every solution of a 6R chain whose last
// three axes meet at one point (spherical wrist).
//
// The derivation, the equation labels (F), (I), (L), (Q), (B), (Q'), (B') and
// the tolerances are those of python/spotkin/reference/ik3r.py, which the tests
// compare this against. Two changes of representation, for speed:
//  - revolute values are carried as (cos q, sin q) until the end, so the back
//    substitution and the Newton polish need no trigonometric call;
//  - the quartic (Q) in e^{i q3} is solved in closed form (Ferrari) in
//    t = tan((q3 - phi) / 2), with phi chosen so that the leading coefficient
//    is the largest of the five samples of P (no root at t = infinity).
// For speed, batches of all-revolute chains run each step across 16 targets
// at once (Position3::solve_block, SphericalWrist6::solve_block), with a fixed
// set of 4 candidates per target and branch-free selects, so that the compiler
// vectorises across targets; only the quartic's roots, the rare Newton steps
// and the rare merges of near-equal solutions go target by target. solve()
// stays the one-target form (and the path of chains with prismatic joints).
//
// The pieces live in spotkin/chain_ik/: common.hpp, position3.hpp, spherical_wrist.hpp,
// batch.hpp.
#pragma once

#include "spotkin/chain_ik/batch.hpp"
