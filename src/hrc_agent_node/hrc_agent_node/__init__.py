"""The robot side of hrc: task tree, hierarchical reward, strategies, PPO, the agent node."""
