#pragma once
// The commanded feed of a liquefier experiment as the firmware's planner runs it: the
// extrude-only moves recorded with the load cell, each accelerated and decelerated at the
// extrude-only acceleration the experiment records (Experiment::excitation), stopping between
// moves where that firmware stops them (Klipper: a junction with an extrude-only move is a full
// stop, toolhead.py) and otherwise joined at the lower of the two speeds (straight on: Klipper's
// calc_junction, Marlin's planner.cpp), as a constant-acceleration (trapezoidal) profile. The
// analysis drives the whole-record liquefier model with it (ident/feed_track.hpp).

#include "tunekit/ident/feed_track.hpp"
#include "tunekit/protocols/experiments.hpp"

namespace tunekit::protocols {

/// The track of the moves between ";@record load_cell on" and "off", in seconds from the first
/// such move's start; empty when the experiment records no load cell, has no extrude-only moves
/// there, or does not record its extrude-only acceleration.
ident::FeedTrack planned_feed_track(const Experiment& e);

}  // namespace tunekit::protocols
