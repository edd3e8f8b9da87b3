"""splatedit.app"""
