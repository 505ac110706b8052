"""The mechanism language: a template (TOML) checked against the schema and the domain, compiled
step by step into a symbolic model of Excel formulas (one module per step type in steps/)."""
