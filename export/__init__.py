"""The export stage (PyTorch): training, evaluation, ONNX export and quantization. Never on the board."""
