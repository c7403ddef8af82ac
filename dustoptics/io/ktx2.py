from dustoptics._deprecated import alias_module

alias_module(__name__, "dustoptics.io.textures.ktx2")
