"""The EWA surface-splat renderer (Botsch & Kobbelt 2005, Sect. 7): uploads, pre-pass, passes, progressive frames, headless PNG."""
