"""The paper's baseline agent (A2C, CNN + GRU), its training, evaluation and tools."""
