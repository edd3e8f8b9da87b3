"""splatedit.render.vk"""
