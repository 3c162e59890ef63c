"""Household robots: SafeAgentBench's 17 actions, AI2-THOR-style scenes, a symbolic executor, planners."""
