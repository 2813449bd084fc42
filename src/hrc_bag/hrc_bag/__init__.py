"""Recording, replay and offline analysis of hrc sessions (MCAP, rosbag2-compatible)."""
