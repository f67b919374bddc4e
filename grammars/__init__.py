"""The Lark grammar of the motion-script language, shipped inside the wheel as armctl.grammars."""
