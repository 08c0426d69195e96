"""Beacon survey (issue 14): where each panel of a room hangs, from frames taken from the floor.

One stage per module, arrows pointing down: `run` chains `sightings` (named panels and their
image points, through `server.rooms` and the one-panel pipeline), `chain` (the graph from the
anchor and a start), `adjust` (the bundle adjustment), `bearing` (the map's compass bearing);
`rules` holds the tunables and the two ways a survey ends without a map. docs/survey.md.
"""
