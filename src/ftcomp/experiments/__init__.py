"""The paper's experiments as functions returning data (gravity, placement) and the demo."""
