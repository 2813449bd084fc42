import glob
import os

from setuptools import find_packages, setup

package_name = 'hrc_bringup'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        # Every node's parameter file, for `hrc session` outside a checkout.
        ('share/' + package_name + '/params',
         glob.glob(os.path.join('..', '..', 'params', '*.yaml'))),
        # the learning configurations (hrc session --learning NAME)
        ('share/' + package_name + '/params/learning',
         glob.glob(os.path.join('..', '..', 'params', 'learning', '*.yaml'))),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='hrc developers',
    maintainer_email='hrc@example.org',
    description='Session and experiment runners of the hrc graph.',
    license='Apache-2.0',
    entry_points={'console_scripts': [
        # the one command line (hrc --help); the nodes keep their own executables
        'hrc = hrc_bringup.cli:main',
    ]},
)
