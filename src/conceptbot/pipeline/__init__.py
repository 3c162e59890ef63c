"""The ConceptBot pipeline: relation retrieval and filtering, calibration."""
