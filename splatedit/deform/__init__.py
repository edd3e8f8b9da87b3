"""splatedit.deform"""
