# Run at install time, before anything is written (cmake/IrdistInstall.cmake includes it through
# install(CODE)): the install never writes through a symbolic link. Every folder it writes into
# below the prefix, and every file or folder already inside irdist's own folders, must not be a
# link; a link there (a linked share/irdist/recipes, say) stops the install before the first
# write, naming the link. The prefix itself may be a link (/usr/local -> /opt/local).
#   irdist_refuse_links(PREFIX REL_DIR... ): REL_DIRs relative to PREFIX; the last path component
#   of each is irdist's own folder (or file), searched whole.
cmake_policy(SET CMP0009 NEW)  # GLOB_RECURSE lists links, never follows them
function(irdist_refuse_links prefix)
  foreach(rel IN LISTS ARGN)
    set(path "${prefix}")
    string(REPLACE "/" ";" parts "${rel}")
    foreach(part IN LISTS parts)
      set(path "${path}/${part}")
      if(IS_SYMLINK "${path}")
        message(FATAL_ERROR "irdist install: ${path} is a symbolic link; the install never writes "
          "through one. Remove the link (or install into another --prefix); nothing was written.")
      endif()
    endforeach()
    if(IS_DIRECTORY "${path}")
      file(GLOB_RECURSE entries LIST_DIRECTORIES true "${path}/*")
      foreach(entry IN LISTS entries)
        if(IS_SYMLINK "${entry}")
          message(FATAL_ERROR "irdist install: ${entry} is a symbolic link; the install never "
            "writes through one. Remove it (or install into another --prefix); nothing was "
            "written.")
        endif()
      endforeach()
    endif()
  endforeach()
endfunction()
