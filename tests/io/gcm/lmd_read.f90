! Reads an LMD Mars PCM dust optical-property file with the PCM's own read loop and prints
! what it read, one number a line (es24.16): nwvl, nsize, wvl, radiusdyn, ep, omeg, gfactor.
!
! The two DO WHILE loops are the read loop of the LMD Mars PCM's phymars/suaer.F90 (sections
! "1.2 Allocate the optical property table" and "1.3 Read the data"), with their READ,
! BACKSPACE and test statements as they stand; only the error messages are left out and
! nsize(iaer,idomain) is a scalar here.  Source: a public copy of suaer.F90 (the PCM's
! "dust_doubleq" case reads optprop_dustvis_TM_n50.dat and optprop_dustir_n50.dat this way).
program lmd_read
  implicit none
  integer, parameter :: file_unit = 60
  character(len=100) :: scanline
  character(len=512) :: path
  integer :: jfile, read_ok, nwvl, nsize, isize, i
  logical :: endwhile
  real, allocatable :: wvl(:), radiusdyn(:), ep(:,:), omeg(:,:), gfactor(:,:)

  call get_command_argument(1, path)
  open(unit=file_unit, file=trim(path), form='formatted')

  jfile = 1
  endwhile = .false.
  do while (.not.endwhile)
    read(file_unit,*,iostat=read_ok) scanline
    if (read_ok.ne.0) stop 2
    if ((scanline(1:1) .ne. '#').and.(scanline(1:1) .ne. ' ')) then
      backspace(file_unit)
      select case (jfile)
      case(1)
        read(file_unit,*,iostat=read_ok) nwvl
        if (read_ok.ne.0) stop 3
        jfile = jfile+1
      case(2)
        read(file_unit,*,iostat=read_ok) nsize
        if (read_ok.ne.0) stop 4
        endwhile = .true.
      case default
        stop 5
      end select
    endif
  enddo

  allocate(wvl(nwvl), radiusdyn(nsize), ep(nwvl,nsize), omeg(nwvl,nsize), gfactor(nwvl,nsize))

  jfile = 1
  endwhile = .false.
  do while (.not.endwhile)
    read(file_unit,*) scanline
    if ((scanline(1:1) .ne. '#').and.(scanline(1:1) .ne. ' ')) then
      backspace(file_unit)
      select case (jfile)
      case(1)
        read(file_unit,*) wvl
        jfile = jfile+1
      case(2)
        read(file_unit,*) radiusdyn
        jfile = jfile+1
      case(3)
        isize = 1
        do while (isize .le. nsize)
          read(file_unit,*) scanline
          if ((scanline(1:1) .ne. '#').and.(scanline(1:1) .ne. ' ')) then
            backspace(file_unit)
            read(file_unit,*) ep(:,isize)
            isize = isize + 1
          endif
        enddo
        jfile = jfile+1
      case(4)
        isize = 1
        do while (isize .le. nsize)
          read(file_unit,*) scanline
          if ((scanline(1:1) .ne. '#').and.(scanline(1:1) .ne. ' ')) then
            backspace(file_unit)
            read(file_unit,*) omeg(:,isize)
            isize = isize + 1
          endif
        enddo
        jfile = jfile+1
      case(5)
        isize = 1
        do while (isize .le. nsize)
          read(file_unit,*) scanline
          if ((scanline(1:1) .ne. '#').and.(scanline(1:1) .ne. ' ')) then
            backspace(file_unit)
            read(file_unit,*) gfactor(:,isize)
            isize = isize + 1
          endif
        enddo
        endwhile = .true.
      case default
        stop 6
      end select
    endif
  enddo
  close(file_unit)

  print '(i0)', nwvl
  print '(i0)', nsize
  print '(es24.16)', wvl
  print '(es24.16)', radiusdyn
  print '(es24.16)', (ep(:,i), i=1,nsize)
  print '(es24.16)', (omeg(:,i), i=1,nsize)
  print '(es24.16)', (gfactor(:,i), i=1,nsize)
end program lmd_read
