"""SafeAgentBench: hazardous-task rejection and safe-task success with the 17 household actions."""
