"""splatedit.select"""
