// SPDX-License-Identifier: Apache-2.0
// The cutters the arm can carry, as ToolGeometry (core/trajectory.h): collision capsules in the
// flange frame and the tool-centre point (TCP). Pure functions; thread-safe.
//
// TCP frame convention (both tools):
//   - TCP z is the tool axis, pointing away from the flange (flange z, the UR's tool direction).
//   - The cane crosses the TCP along TCP y, perpendicular to z (for a cut pose tilted about x,
//     cut_motion.h, the cut is oblique by the tilt): at the cut pose the cane axis
//     passes through the TCP origin, parallel to TCP y (either sign).
//   - Mill end (Botterill et al. 2017 section 3.4, a spinning router bit): the TCP is on the bit
//     axis in the middle of the flute; a cut is a straight sweep of the TCP along TCP x, centred on
//     the cane (CutMotionOptions::sweep_m, ~0.10 m), orientation fixed. x = y cross z.
//   - Secateur (powered pruning shears): the TCP is in the throat between the open jaws, which
//     open along TCP x; a cut is an approach along +z from approach_m behind the cut, a close (no
//     arm motion) and a retract back along -z. The cane lies between the open jaws: no capsule of
//     the tool touches it (cut_motion.h checks this); only the closing blades cut it.
// Dimensions are representative catalogue values (stated per field), not measurements of one
// product; replace them with the measured tool when it is built.
#pragma once

#include <string_view>

#include "absl/status/status.h"
#include "core/trajectory.h"

namespace vb::plan {

inline constexpr char kMillEndToolName[] = "mill_end";
inline constexpr char kSecateurToolName[] = "secateur";

struct MillEndOptions {
  // Spindle motor body (compact 65 mm trim-router / spindle motor class, ~0.18 m long).
  double body_length_m = 0.18;   // flange face to the motor's nose
  double body_radius_m = 0.033;  // ~65 mm diameter housing
  // Collet nut below the motor nose (ER11-class collet nut, ~19 mm across).
  double collet_length_m = 0.02;
  double collet_radius_m = 0.0095;
  // Router bit (6 mm straight / spiral bit; ~25 mm cutting flute, ~40 mm out of the collet).
  double bit_length_m = 0.04;    // exposed length, collet to tip
  double bit_radius_m = 0.003;
  double flute_length_m = 0.025; // cutting part at the tip end; the TCP is at its middle

  // INVALID_ARGUMENT naming the field: non-finite or non-positive values, flute longer than the
  // exposed bit, bit wider than the collet.
  absl::Status Validate() const;
};

struct SecateurOptions {
  // Body: motor and gearbox housing of a powered pruning shear (~0.05 m across, ~0.15 m long).
  double body_length_m = 0.15;
  double body_radius_m = 0.028;
  // Jaws: blade and anvil, ~0.07 m long, opening ~0.035 m (shears cutting up to ~30 mm canes).
  double jaw_length_m = 0.07;
  double jaw_opening_m = 0.035;   // clear gap between the open jaws
  double jaw_radius_m = 0.006;    // half the thickness of each jaw (enclosing capsule)
  double tcp_depth_m = 0.025;     // TCP distance from the jaw root (throat) toward the tips

  // INVALID_ARGUMENT naming the field: non-finite or non-positive values, TCP beyond the tips.
  absl::Status Validate() const;
};

// The mill end: body capsule on the flange axis, collet, thin bit beyond it; TCP at the middle of
// the flute, axes as the flange's. Options are assumed valid (Validate() first).
ToolGeometry MillEndTool(const MillEndOptions& options = {});
// The secateur: body capsule on the flange axis and two jaw capsules at x = +-(opening/2 + jaw
// radius); TCP on the axis, tcp_depth_m beyond the jaw root. Options are assumed valid.
ToolGeometry SecateurTool(const SecateurOptions& options = {});

enum class CutStroke {
  kSweep,                 // mill end: straight sweep along TCP x through the cane
  kApproachCloseRetract,  // secateur: along TCP z to the cane and back
};
// The stroke of a tool, from its name (the only tool identity the trajectory format carries):
// "secateur" -> kApproachCloseRetract, anything else (the mill end) -> kSweep.
CutStroke StrokeOf(const ToolGeometry& tool);

}  // namespace vb::plan
