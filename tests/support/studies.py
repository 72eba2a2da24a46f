"""Small study files shared by the optimisation tests (few samples, seconds to solve)."""

SMALL = """
name = "small"
objective = "disc_radius"
[free]
magnet_length_mm = [0.3, 1.5]
magnet_gap_mm = [0.0, 1.0]
wire_outer_diameter_mm = [0.3, 0.6]
external_distance_mm = [70.0, 200.0]
[materials]
catheter = ["ptfe"]
wire = ["niti"]
[constraints]
twist_limit_deg = 20.0
neutral_tolerance_mm = 0.8
magnet_clearance_mm = 5.0
[solver]
starts = 2
configurations = 24
neutral_configurations = 8
"""
"""Two starts, 24 + 8 + 8 sampled configurations, four free quantities: a few seconds."""
